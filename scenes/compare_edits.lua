-- The edits every indirect method is compared under (afterglow compare-methods,
-- docs/compare_methods.md), for scenes/compare.json and scenes/conference.json: frames 10-40 an
-- object slides, 50-70 a light moves, at 80 a surface changes colour; then the scene is still
-- (run to frame 150). The state follows from `frame` alone, and each item is edited only in the
-- frames it changes, so every method sees exactly these edits.

local slide = {10, 40}
local light_move = {50, 70}
local recolour = 80

-- Per scene (the first whose object exists): what slides and by how much, which light moves and
-- by how much, what turns blue. Offsets in the scene's unit.
local setups = {
    -- compare.json (mm): the cube ends 12 mm short of the red wall, clear of the tall block; the
    -- light moves 150 mm towards the red wall, which then turns blue.
    {object = "cube", offset = {254.5, 0, -59}, light = "ceiling", light_offset = {150, 0, 0},
     recolour = "left_wall"},
    -- conference.json (m): the box slides 1.4 m along the table towards the camera, the second
    -- lamp moves 1 m along the table, the box turns blue.
    {object = "box", offset = {1.4, 0, 0}, light = "lamp_2", light_offset = {1.0, 0, 0},
     recolour = "box"},
}
local blue = {0.1, 0.15, 0.6}

local setup, object, lamp, surface
local object_start, lamp_start, original = {}, {}, {}
local object_s, lamp_s, recoloured = 0, 0, false

-- 0 before the span, 1 after it, eased in and out between.
local function progress(span, frame)
    local t = math.min(math.max((frame - span[1]) / (span[2] - span[1]), 0), 1)
    return t * t * (3 - 2 * t)
end

local function place(item, start, offset, s)
    item:set_position(start[1] + s * offset[1], start[2] + s * offset[2], start[3] + s * offset[3])
end

function on_start(scene)
    for _, candidate in ipairs(setups) do
        local ok, found = pcall(scene.object, scene, candidate.object)
        if ok then
            setup, object = candidate, found
            break
        end
    end
    if not setup then error("compare_edits.lua: the scene has neither a 'cube' nor a 'box'") end
    lamp = scene:light(setup.light)
    surface = scene:object(setup.recolour)
    object_start = {object:position()}
    lamp_start = {lamp:position()}
    original = {surface:albedo()}
end

function on_frame(scene, frame, time)
    local s = progress(slide, frame)
    if s ~= object_s then
        place(object, object_start, setup.offset, s)
        object_s = s
    end
    local l = progress(light_move, frame)
    if l ~= lamp_s then
        place(lamp, lamp_start, setup.light_offset, l)
        lamp_s = l
    end
    local wanted = frame >= recolour
    if wanted ~= recoloured then
        local c = wanted and blue or original
        surface:set_albedo(c[1], c[2], c[3])
        recoloured = wanted
    end
end
