-- scenes/vpl_table_bunny.json: Barczak 2006's table room (§5.4): the Stanford bunny slides across
-- the table and back over 200 frames (0.8 m each way, 8 mm a frame), so the VPLs on the table,
-- the walls and the bunny, and the shadow maps of every VPL that sees it, must follow. Lengths in m.

local frames = 200
local bunny
local start = {}

function on_start(scene)
    bunny = scene:object("bunny")
    start[1], start[2], start[3] = bunny:position()
end

function on_frame(scene, frame, time)
    local t = (frame % frames) / frames
    local s = t < 0.5 and 2 * t or 2 - 2 * t
    bunny:set_position(start[1] + 0.8 * s, start[2], start[3])
end
