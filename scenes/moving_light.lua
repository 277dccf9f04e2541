-- scenes/moving_light.json: a stand-in for Gautron 2006's Moving Light (Table 5.2, 0.95x): a point
-- light circling 1.2 m above a floor of 8 x 8 tiles (two albedos), a box, a pillar and a back
-- wall. Every record sees the light move, so temporal caching can keep few of them. Lengths in m.

local frames = 200
local radius = 1.0
local lamp

function on_start(scene)
    lamp = scene:light("lamp")
end

function on_frame(scene, frame, time)
    local angle = 2 * math.pi * (frame % frames) / frames
    lamp:set_position(radius * math.cos(angle), 1.2, 0.5 + radius * math.sin(angle))
end
