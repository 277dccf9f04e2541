-- scenes/two_rooms.json: the lights of room a ("a1", "a2") go off at frame 30 and room b's stay
-- on (Larsen Fig. 14.1, bottom). Switching off removes those lights' photons (ch. 9).

local off_at = 30
local names = {"a1", "a2"}
local lights = {}

function on_start(scene)
    for i, name in ipairs(names) do
        lights[i] = scene:light(name)
    end
end

-- The state follows from the frame, so looping back to frame 0 turns them on again; a light is
-- edited only when its state changes.
function on_frame(scene, frame, time)
    local on = frame < off_at
    for _, light in ipairs(lights) do
        if light:enabled() ~= on then
            light:set_enabled(on)
        end
    end
end
