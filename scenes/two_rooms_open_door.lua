-- scenes/two_rooms.json: the door swings open by 90 degrees over 40 frames from frame 10, then
-- stays open; light from each room then reaches the other (Larsen Fig. 14.1).
-- The door's origin is its hinge (the scene's "offset"), so turning it about +y swings it.

local first, frames, angle = 10, 40, 90  -- +90 about +y takes the door's +z edge to +x: room b

local door
local opened = 0  -- degrees turned so far

local function smoothstep(t)
    t = math.min(math.max(t, 0), 1)
    return t * t * (3 - 2 * t)
end

function on_start(scene)
    door = scene:object("door")
end

-- The wanted angle depends on the frame alone, and the door turns by what is missing, so frames
-- may come in any order (a viewer that loops back) and it never turns past 90 degrees.
function on_frame(scene, frame, time)
    local wanted = angle * smoothstep((frame - first + 1) / frames)
    if wanted ~= opened then
        door:rotate(0, 1, 0, wanted - opened)
        opened = wanted
    end
end
