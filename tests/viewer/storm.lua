-- scenes/cornell.json: an invalidation storm for measuring frame times (docs/viewer.md). Both
-- dynamic objects circle around their start every frame, so every frame invalidates the photon
-- groups whose paths they cross, moves the caustics and queues IIM texels around them.
local cube, sphere
local c0, s0 = {}, {}
local radius = 40  -- mm

function on_start(scene)
    cube = scene:object("cube")
    sphere = scene:object("sphere")
    c0[1], c0[2], c0[3] = cube:position()
    s0[1], s0[2], s0[3] = sphere:position()
end

function on_frame(scene, frame, time)
    local a = 2 * math.pi * frame / 90  -- one turn every 90 frames
    cube:set_position(c0[1] + radius * math.cos(a), c0[2], c0[3] + radius * math.sin(a))
    sphere:set_position(s0[1] - radius * math.cos(a), s0[2], s0[3] - radius * math.sin(a))
end
