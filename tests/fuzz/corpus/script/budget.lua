function on_start(scene) scene:object("floor"):translate(1, 0, 0) end
function on_frame() local t = {} for i = 1, 1e9 do t[i] = i end end
