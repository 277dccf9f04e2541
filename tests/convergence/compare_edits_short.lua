-- scenes/compare.json's edits (scenes/compare_edits.lua) on a short clock, for the CTest
-- convergence.compare_methods (tests/convergence/compare_methods_test.sh): frames 3-9 the cube
-- slides, 14-19 the light moves, at 25 the red wall turns blue; run to frame 36.

local slide = {3, 9}
local light_move = {14, 19}
local recolour = 25
local blue = {0.1, 0.15, 0.6}

local cube, lamp, wall
local cube_start, lamp_start, red = {}, {}, {}
local cube_s, lamp_s, recoloured = 0, 0, false

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
        cube:set_position(cube_start[1] + 254.5 * s, cube_start[2], cube_start[3] - 59 * s)
        cube_s = s
    end
    local l = progress(light_move, frame)
    if l ~= lamp_s then
        lamp:set_position(lamp_start[1] + 150 * l, lamp_start[2], lamp_start[3])
        lamp_s = l
    end
    local wanted = frame >= recolour
    if wanted ~= recoloured then
        local c = wanted and blue or red
        wall:set_albedo(c[1], c[2], c[3])
        recoloured = wanted
    end
end
