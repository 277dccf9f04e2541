-- scenes/two_rooms.json: the door opens by 90 degrees in one frame (frame 20) and stays open; light
-- from each room reaches the other at once (the step version of two_rooms_open_door.lua).
-- The door's origin is its hinge (the scene's "offset"), so turning it about +y swings it.

local at, angle = 20, 90  -- +90 about +y takes the door's +z edge to +x: room b

local door
local opened = 0  -- degrees turned so far

function on_start(scene)
    door = scene:object("door")
end

-- The wanted angle depends on the frame alone, so looping back to frame 0 shuts the door again.
function on_frame(scene, frame, time)
    local wanted = frame >= at and angle or 0
    if wanted ~= opened then
        door:rotate(0, 1, 0, wanted - opened)
        opened = wanted
    end
end
