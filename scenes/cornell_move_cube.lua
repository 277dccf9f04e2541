-- scenes/cornell.json: the cube slides across the floor during frames 1-60, then stops.
-- A rigid move of one dynamic object, the basic edit of Larsen ch. 14. Lengths in mm.

local frames = 60
-- From (185.5, 82.5, 169) to (440, 82.5, 110). The cube, turned -17 degrees, reaches 103 mm
-- from its centre in x and z: it ends 12 mm short of the red wall (x = 555), and moving away
-- from the camera's side it keeps at least 16 mm from the glass sphere (radius 90 at
-- (368.5, 351.5) in x, z).
local offset = {254.5, 0, -59}

local cube
local start = {}
local placed = 0  -- fraction of the slide already applied

-- Eases in and out, so the cube starts and stops without a jolt.
local function smoothstep(t)
    t = math.min(math.max(t, 0), 1)
    return t * t * (3 - 2 * t)
end

function on_start(scene)
    cube = scene:object("cube")
    start[1], start[2], start[3] = cube:position()
end

-- Edits only while the cube moves, so frames after 60 leave the scene's versions alone.
function on_frame(scene, frame, time)
    local s = smoothstep(frame / frames)
    if s ~= placed then
        cube:set_position(start[1] + s * offset[1], start[2] + s * offset[2],
                          start[3] + s * offset[3])
        placed = s
    end
end
