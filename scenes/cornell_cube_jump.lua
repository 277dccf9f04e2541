-- scenes/cornell.json: the cube jumps in one frame (frame 20) to where cornell_move_cube.lua
-- slides it, 261 mm away ((254.5, 0, -59) in x, y, z), and stays there. A step edit: every photon
-- group whose stored path crosses the old or the new placement must be invalidated in that frame.

local at = 20
local offset = {254.5, 0, -59}

local cube
local start = {}
local jumped = false

function on_start(scene)
    cube = scene:object("cube")
    start[1], start[2], start[3] = cube:position()
end

-- The placement follows from the frame, so looping back to frame 0 puts the cube back; the cube
-- is edited only in the frame its placement changes.
function on_frame(scene, frame, time)
    local wanted = frame >= at
    if wanted ~= jumped then
        local s = wanted and 1 or 0
        cube:set_position(start[1] + s * offset[1], start[2] + s * offset[2], start[3] + s * offset[3])
        jumped = wanted
    end
end
