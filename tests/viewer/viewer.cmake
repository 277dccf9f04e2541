# Viewer tests (label gl): `afterglow view` under a virtual X server (xvfb-run), driven by a Lua
# script or by recorded input (--replay). Skipped (exit 77) where xvfb-run is missing or no GL 4.5
# window can be made; never passed then.
add_executable(viewer_check ${CMAKE_CURRENT_LIST_DIR}/viewer_check.cpp)
target_link_libraries(viewer_check PRIVATE ag_warnings ag_shared nlohmann_json::nlohmann_json)

function(ag_viewer_test name)
  add_test(NAME viewer.${name}
           COMMAND ${CMAKE_CURRENT_LIST_DIR}/viewer_test.sh ${name} $<TARGET_FILE:afterglow>
                   $<TARGET_FILE:viewer_check> ${PROJECT_BINARY_DIR}/viewer_test/${name}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(viewer.${name} PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
  ag_test_timeout(viewer.${name} 120)
endfunction()

# cornell_move_cube.lua through the viewer: screenshots, not blank, the cube's shadow moved.
ag_viewer_test(script)
# Recorded clicks drag the cube: it moved, and IIM texels around it were gathered again.
ag_viewer_test(replay)
# gpu_pm's photon-tile view draws a picture.
ag_viewer_test(photon_tiles)
# The media view shows a slice of the media method's grids (docs/media.md).
ag_viewer_test(media)
# The VPL view: the VPLs drawn over their sum.
ag_viewer_test(vpls)
