function on_frame(scene) scene:light("ceiling"):set_position(2^63, 500, 200) end
