-- scenes/cornell.json: the red left wall turns blue in one frame (frame 20) and stays blue. Every
-- photon group with a hit on the wall saw the old albedo in its Russian roulette and colour, so
-- those groups are invalidated in that frame (Larsen ch. 9).

local at = 20
local blue = {0.1, 0.15, 0.6}

local wall
local original = {}
local changed = false

function on_start(scene)
    wall = scene:object("left_wall")
    original[1], original[2], original[3] = wall:albedo()
end

-- The colour follows from the frame, so looping back to frame 0 makes the wall red again; the
-- wall is edited only in the frame its colour changes (albedo is stored in single precision, so
-- the state is kept here rather than read back and compared).
function on_frame(scene, frame, time)
    local wanted = frame >= at
    if wanted ~= changed then
        local c = wanted and blue or original
        wall:set_albedo(c[1], c[2], c[3])
        changed = wanted
    end
end
