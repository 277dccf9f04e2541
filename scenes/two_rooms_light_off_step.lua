-- scenes/two_rooms.json: light "a1" of room a goes off in one frame (frame 20); the other three
-- stay on. Switching off removes that light's photons at once (Larsen ch. 9).

local at = 20
local light

function on_start(scene)
    light = scene:light("a1")
end

-- The state follows from the frame, so looping back to frame 0 turns it on again; the light is
-- edited only when its state changes.
function on_frame(scene, frame, time)
    local on = frame < at
    if light:enabled() ~= on then
        light:set_enabled(on)
    end
end
