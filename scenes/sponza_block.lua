-- scenes/sponza.json: the orange block slides 6 m along the atrium's floor through the sunlit
-- patch during frames 1-90, then stops. Lengths in m.

local frames = 90
local offset = {6, 0, 0}

local block
local start = {}
local placed = 0  -- fraction of the slide already applied

local function smoothstep(t)
    t = math.min(math.max(t, 0), 1)
    return t * t * (3 - 2 * t)
end

function on_start(scene)
    block = scene:object("block")
    start[1], start[2], start[3] = block:position()
end

-- Edits only while the block moves, so later frames leave the scene's versions alone.
function on_frame(scene, frame, time)
    local s = smoothstep(frame / frames)
    if s ~= placed then
        block:set_position(start[1] + s * offset[1], start[2] + s * offset[2],
                           start[3] + s * offset[3])
        placed = s
    end
end
