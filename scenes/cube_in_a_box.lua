-- scenes/cube_in_a_box.json: Gautron 2006's Cube in a Box (Table 5.2: 24 polygons, 400 frames,
-- a^t = 0.05, dt_max = 20). The cube circles the floor once in 400 frames (radius 0.9 m about
-- (0, 0.5), about 1.4 cm a frame). Lengths in m.

local frames = 400
local radius = 0.9
local centre = {0, 0.5}
local cube

function on_start(scene)
    cube = scene:object("cube")
end

function on_frame(scene, frame, time)
    local angle = 2 * math.pi * (frame % frames) / frames
    cube:set_position(centre[1] + radius * math.cos(angle), 0.3, centre[2] + radius * math.sin(angle))
end
