-- scenes/bumpy_133k_box.json: the blue box (160 mm) jumps in one frame (frame 20) from the bumpy
-- floor at the front left onto the top of the short block, 313 mm away ((-244.5, 185, 59) in x,
-- y, z), and stays there. A step edit on a 131,000-triangle scene: the groups whose stored paths
-- cross the old or the new placement must be invalidated in that frame.

local at = 20
local offset = {-244.5, 185, 59}

local box
local start = {}
local jumped = false

function on_start(scene)
    box = scene:object("box")
    start[1], start[2], start[3] = box:position()
end

-- The placement follows from the frame, so looping back to frame 0 puts the box back; the box
-- is edited only in the frame its placement changes.
function on_frame(scene, frame, time)
    local wanted = frame >= at
    if wanted ~= jumped then
        local s = wanted and 1 or 0
        box:set_position(start[1] + s * offset[1], start[2] + s * offset[2], start[3] + s * offset[3])
        jumped = wanted
    end
end
