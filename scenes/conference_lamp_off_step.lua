-- scenes/conference.json: lamp_4 (the one over the far end of the room) goes off in one frame
-- (frame 20); the other three stay on. A step edit whose indirect change covers a large part of
-- the 39,505-texel lightmap, unlike the box jump, whose effect on the indirect image is within
-- the settle tolerance at once.

local at = 20
local light

function on_start(scene)
    light = scene:light("lamp_4")
end

-- The state follows from the frame, so looping back to frame 0 turns it on again; the light is
-- edited only when its state changes.
function on_frame(scene, frame, time)
    local on = frame < at
    if light:enabled() ~= on then
        light:set_enabled(on)
    end
end
