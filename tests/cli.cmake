# Command-line tests: the built `afterglow` binary, its exit codes and messages.
set(AG_BIN $<TARGET_FILE:afterglow>)
set(AG_EXPECT ${CMAKE_CURRENT_SOURCE_DIR}/cli/expect.sh)

function(ag_cli_test name code regex)
  add_test(NAME cli.${name} COMMAND ${AG_EXPECT} ${code} "${regex}" ${AG_BIN} ${ARGN}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(cli.${name} PROPERTIES LABELS unit)
endfunction()

ag_cli_test(help 0 "info +Load a scene" --help)
ag_cli_test(no_command 2 "usage: afterglow COMMAND")
ag_cli_test(unknown_command 2 "unknown command 'frobnicate'" frobnicate)
ag_cli_test(info_help 0 "usage: afterglow info SCENE" info --help)
ag_cli_test(export_help 0 "usage: afterglow export SCENE" export --help)
ag_cli_test(unknown_option 2 "unknown option '--bogus'" info --bogus scenes/cornell.json)
ag_cli_test(missing_argument 2 "missing argument" info)
ag_cli_test(missing_scene 1 "no_such_scene.json" info no_such_scene.json)
ag_cli_test(export_needs_output 2 "missing -o" export scenes/cornell.json)
ag_cli_test(info_cornell 0 "surfaces +[0-9]+.*" info scenes/cornell.json --objects)
ag_cli_test(info_two_rooms 0 "lights +4" info scenes/two_rooms.json)
# Larsen Table 14.2: ~13,000 and ~133,000 polygons.
ag_cli_test(info_bumpy_13k 0 "triangles +(1[23][0-9][0-9][0-9]|14000)$" info scenes/bumpy_13k.json)
ag_cli_test(info_bumpy_133k 0 "triangles +(12[5-9][0-9][0-9][0-9]|13[0-9][0-9][0-9][0-9]|140000)$"
            info scenes/bumpy_133k.json)
add_test(NAME cli.export_cornell COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/export_test.sh ${AG_BIN}
         scenes/cornell.json WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.export_cornell PROPERTIES LABELS unit)

# Rendering through OSMesa (label gl): a tiny render writes its images; bad flags are exit 2.
add_test(NAME cli.render_cornell COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/render_test.sh ${AG_BIN}
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.render_cornell PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
ag_cli_test(render_bad_gl 2 "--gl: unknown GL backend 'vulkan'" render scenes/cornell.json -o x.exr --gl vulkan)
ag_cli_test(render_bad_size 2 "--size expects WxH" render scenes/cornell.json -o x.exr --size 12by5)
ag_cli_test(render_needs_exr 2 "ending in .exr" render scenes/cornell.json -o x.png)
ag_cli_test(render_bad_gather 2 "--gather expects gl, cpu or auto" render scenes/cornell.json -o x.exr --gather gpu)
