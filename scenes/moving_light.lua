-- scenes/moving_light.json: Gautron 2006's Moving Light (Table 5.2: 400 frames, 0.95x): Cube in
-- a Box's room with a floor of 8 x 8 tiles (two albedos; his floor is a texture, so his count is
-- 24 polygons and ours 152) and the cube standing still; the point light circles 1 m about the
-- room's centre, 2.4 m up, once in 400 frames. Every record sees the light move. Lengths in m.

local frames = 400
local lamp

function on_start(scene)
    lamp = scene:light("lamp")
end

function on_frame(scene, frame, time)
    local angle = 2 * math.pi * (frame % frames) / frames
    lamp:set_position(math.cos(angle), 2.4, 0.5 + math.sin(angle))
end
