-- scenes/spheres_66.json: Gautron 2006's Spheres (Table 5.2: 66 bouncing spheres, 64K polygons,
-- 200 frames, a^t = 0.05, dt_max = 5; his back wall is glossy, ours diffuse). Cube in a Box's
-- room, 66 icospheres of 1280 triangles (84K in all), each bouncing on the floor with its own
-- period and phase. Lengths in m.

local spheres = {}
local base = {}

function on_start(scene)
    for k = 0, 65 do
        local s = scene:object("sphere_" .. k)
        spheres[k] = s
        local x, y, z = s:position()
        base[k] = {x, z}
    end
end

function on_frame(scene, frame, time)
    for k = 0, 65 do
        local period = 40 + (k * 7) % 30
        local phase = (frame + k * 13) % period / period
        local height = 0.1 + 0.6 * 4 * phase * (1 - phase)
        spheres[k]:set_position(base[k][1], height, base[k][2])
    end
end
