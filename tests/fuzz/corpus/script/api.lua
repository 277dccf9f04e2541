local c, s, l
function on_start(scene)
  c = scene:object("cube"); s = scene:object("sphere"); l = scene:light("ceiling")
  local cam = scene:camera()
  scene:set_camera({fov_y = cam.fov_y + 1, eye = {cam.eye[1], cam.eye[2], cam.eye[3] - 1}})
end
function on_frame(scene, frame, time)
  c:translate(1, 0, 0); c:rotate(0, 1, 0, 5); s:set_position(300, 90, 300)
  local r, g, b = l:color(); l:set_color(g, b, r); l:move(0, -1, 0)
  l:set_enabled(frame % 2 == 0); c:set_albedo(0.5, 0.5, 0.5)
  local x, y, z = c:position(); print(c:name(), x, y, z, l:enabled(), c:albedo())
end
