-- scenes/vpl_table_torus.json: Barczak 2006's second mover (§5.2), a torus of 41 × 20 = 820
-- vertices standing on the table, rolls 0.8 m across it and back over 200 frames (8 mm a frame,
-- turning as a wheel of radius 0.21 m would), so the VPLs and every shadow map that sees it must
-- follow. Lengths in m.

local frames = 200
local torus
local start = {}
local last = 0  -- the share of the way done at the last frame

function on_start(scene)
    torus = scene:object("torus")
    start[1], start[2], start[3] = torus:position()
end

function on_frame(scene, frame, time)
    local t = (frame % frames) / frames
    local s = t < 0.5 and 2 * t or 2 - 2 * t
    torus:set_position(start[1] + 0.8 * s, start[2], start[3])
    -- Rolling: a turn of (way / outer radius) about its axis (world z), clockwise going +x.
    torus:rotate(0, 0, 1, -math.deg(0.8 * (s - last) / 0.21))
    last = s
end
