-- The edits of scenes/compare_edits.lua on a short clock for the CTest convergence.compare_methods
-- (tests/convergence/compare_methods_test.sh): frames 3-9 the cube slides, 14-19 the light moves,
-- at 25 the red wall turns blue; run to frame 45. Only the three spans differ from that script.

local slide = {3, 9}
local light_move = {14, 19}
local recolour = 25

local cube_offset = {254.5, 0, -59}  -- ends 12 mm short of the red wall, clear of the tall block
local light_offset = {150, 0, 0}
local blue = {0.1, 0.15, 0.6}

local cube, lamp, wall
local cube_start, lamp_start, red = {}, {}, {}
local cube_s, lamp_s, recoloured = 0, 0, false

-- 0 before the span, 1 after it, eased in and out between.
local function progress(span, frame)
    local t = math.min(math.max((frame - span[1]) / (span[2] - span[1]), 0), 1)
    return t * t * (3 - 2 * t)
end

function on_start(scene)
    cube = scene:object("cube")
    lamp = scene:light("ceiling")
    wall = scene:object("left_wall")
    cube_start = {cube:position()}
    lamp_start = {lamp:position()}
    red = {wall:albedo()}
end

function on_frame(scene, frame, time)
    local s = progress(slide, frame)
    if s ~= cube_s then
        cube:set_position(cube_start[1] + s * cube_offset[1], cube_start[2] + s * cube_offset[2],
                          cube_start[3] + s * cube_offset[3])
        cube_s = s
    end
    local l = progress(light_move, frame)
    if l ~= lamp_s then
        lamp:set_position(lamp_start[1] + l * light_offset[1], lamp_start[2] + l * light_offset[2],
                          lamp_start[3] + l * light_offset[3])
        lamp_s = l
    end
    local wanted = frame >= recolour
    if wanted ~= recoloured then
        local c = wanted and blue or red
        wall:set_albedo(c[1], c[2], c[3])
        recoloured = wanted
    end
end
