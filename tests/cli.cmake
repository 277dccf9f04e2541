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
# Scenes wrapping meshes from ../shared/external-scenes: skipped (exit 77) where the mesh is absent.
set(AG_EXTERNAL ${PROJECT_SOURCE_DIR}/../shared/external-scenes)
function(ag_cli_external_test name file code regex)
  add_test(NAME cli.${name}
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/external_test.sh ${AG_EXTERNAL}/${file} ${code}
                   "${regex}" ${AG_BIN} ${ARGN}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(cli.${name} PROPERTIES LABELS unit SKIP_RETURN_CODE 77)
endfunction()
# Greg Ward's conference room: the file's 331,179 faces, of which 53,627 repeat a vertex or have
# zero area and are dropped, leave 277,552 triangles; the dynamic box adds 12.
ag_cli_external_test(info_conference conference/conference.obj 0
                     "triangles +2775[0-9][0-9]$" info scenes/conference.json)
ag_cli_external_test(info_conference_faces conference/conference.obj 0
                     "dropped 53627 of 331179 faces as degenerate" info scenes/conference.json)
ag_cli_test(info_bumpy_133k_box 0 "objects +9 \\(1 dynamic\\)" info scenes/bumpy_133k_box.json)
# Kwast's box with the Stanford bunny in place of the blocks (69,451 + 10 walls + 320 lamp).
ag_cli_external_test(info_cornell_kwast_bunny stanford-bunny/bun_zipper.ply 0
                     "triangles +69781$" info scenes/cornell_kwast_bunny.json)
add_test(NAME cli.export_cornell COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/export_test.sh ${AG_BIN}
         scenes/cornell.json WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.export_cornell PROPERTIES LABELS unit)

# Rendering through OSMesa (label gl): a tiny render writes its images; bad flags are exit 2.
add_test(NAME cli.render_cornell COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/render_test.sh ${AG_BIN}
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.render_cornell PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
ag_cli_test(render_needs_exr 2 "ending in .exr" render scenes/cornell.json -o x.png)
# The indirect term's per-stage error budget at CI size (docs/fidelity.md, issue #12).
add_test(NAME cli.fidelity_cornell COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.fidelity_cornell PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
# Adaptive lightmap density: contact regions at 48² (docs/fidelity.md, issue #12 item 4).
add_test(NAME cli.fidelity_density COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_density_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.fidelity_density PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
# Density within a chart: only the floor's tiles near the contacts finer (issue #12 item 4).
add_test(NAME cli.fidelity_tiles COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_tiles_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.fidelity_tiles PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
# The AIM's kNN density at chart edges: stage (a) on the rim of the room at 48² (issue #12).
add_test(NAME cli.fidelity_edges COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_edges_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.fidelity_edges PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
# Two independent pt estimators at the same points (fidelity --pt-pixels, docs/fidelity.md).
add_test(NAME cli.fidelity_pt_pixels COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_pt_pixels_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.fidelity_pt_pixels PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
# Issue #12's whole-image bars at 48² with finer texels at contacts and 16 photon sets, against
# pt with light tracing at 1024 spp (docs/fidelity.md "Session 18"); with one photon set two_rooms'
# seed 3 reads 0.985 and fails.
foreach(scene_frames cornell:300 two_rooms:400)
  string(REPLACE ":" ";" sf ${scene_frames})
  list(GET sf 0 scene)
  list(GET sf 1 frames)
  add_test(NAME cli.fidelity_acceptance_${scene}
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/fidelity_acceptance_test.sh ${AG_BIN} ${scene} 1024
                   ${frames} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(cli.fidelity_acceptance_${scene} PROPERTIES LABELS gl SKIP_RETURN_CODE 77)
endforeach()
ag_cli_test(fidelity_bad_reference 1 "no_such.indirect.exr" fidelity scenes/cornell.json
            --reference no_such.exr)
# Values above half float's 65504 survive in the EXR; compare refuses NaN/Inf images (exit 1).
add_test(NAME cli.render_bright COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/cli/bright_render_test.sh
         ${AG_BIN} WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.render_bright PROPERTIES LABELS gl SKIP_RETURN_CODE 77)

# Bad flags are exit 2 with a message naming the flag and what it expects, checked while parsing
# (before the scene loads or a window opens), the same for every command (tools/afterglow/cli.h).
foreach(cmd info export photons render view converge reference compare glinfo bench media)
  ag_cli_test(${cmd}_help 0 "usage: afterglow ${cmd} .*" ${cmd} --help)
  ag_cli_test(${cmd}_help_short 0 "  -h, --help +show this help" ${cmd} -h)
endforeach()
# 4294967328 = 2^32 + 32 used to wrap to 32.
set(bad_sizes 0x5 5x abc 20000x10 12by5 x5 -3x5 5x0 5x5x5 4294967328x32 32x4294967328)
foreach(cmd_args IN ITEMS "render;-o;x.exr" "view" "converge" "reference;-m;pt;-o;x.exr")
  list(GET cmd_args 0 cmd)
  foreach(size IN LISTS bad_sizes)
    ag_cli_test(${cmd}_bad_size_${size} 2
                "--size: expects WxH with positive integers up to 16384, got '${size}'"
                ${cmd_args} scenes/cornell.json --size "${size}")
  endforeach()
  ag_cli_test(${cmd}_unknown_option 2 "afterglow ${cmd}: unknown option '--bogus'"
              ${cmd_args} scenes/cornell.json --bogus 1)
endforeach()
foreach(cmd_args IN ITEMS "render;-o;x.exr" "view" "converge")
  list(GET cmd_args 0 cmd)
  ag_cli_test(${cmd}_bad_gather 2 "--gather: bogus not in .auto,gl,cpu." ${cmd_args}
              scenes/cornell.json --gather bogus)
  ag_cli_test(${cmd}_bad_set 2 "--set: 'photons.groups=0': /photons/groups: expected an integer"
              ${cmd_args} scenes/cornell.json --set photons.groups=0)
endforeach()
ag_cli_test(render_bad_gl 2 "--gl: vulkan not in .osmesa,egl,auto." render scenes/cornell.json -o x.exr --gl vulkan)
ag_cli_test(render_gl_window 2 "--gl: window not in .osmesa,egl,auto." render scenes/cornell.json -o x.exr --gl window)
ag_cli_test(view_gl_osmesa 2 "--gl: osmesa not in .window." view scenes/cornell.json --gl osmesa)
ag_cli_test(glinfo_bad_gl 2 "--gl: vulkan not in .osmesa,egl,auto,window." glinfo --gl vulkan)
ag_cli_test(bench_bad_gl 2 "--gl: vulkan not in" bench frame --gl vulkan)
ag_cli_test(view_bad_view 2 "--view: nope not in .frame,direct" view scenes/cornell.json --view nope)
ag_cli_test(converge_bad_component 2 "--component: nope not in" converge scenes/cornell.json --component nope)
ag_cli_test(reference_bad_method 2 "--method: mc not in .pt,pm." reference scenes/cornell.json -m mc -o x.exr)
ag_cli_test(render_frames_range 2 "--frames: Value 0 not in range 1 to 1000000" render scenes/cornell.json -o x.exr -n 0)
ag_cli_test(render_frames_not_int 2 "--frames: Value 2.5 not in range" render scenes/cornell.json -o x.exr --frames 2.5)
ag_cli_test(render_exposure_nan 2 "--exposure: expects a finite number, got 'nan'" render scenes/cornell.json -o x.exr --exposure nan)
ag_cli_test(render_missing_value 2 "option --frames expects a value \\(N\\)" render scenes/cornell.json -o x.exr --frames)
ag_cli_test(info_flag_value 2 "option --objects takes no value" info scenes/cornell.json --objects=3)
ag_cli_test(bench_repeat_range 2 "--repeat: Value 0 not in range 1 to 1000" bench knn --repeat 0)
ag_cli_test(info_set_bad_key 2 "--set: 'photons.nope=1': /photons/nope: unknown key" info scenes/cornell.json --set photons.nope=1)
ag_cli_test(info_set_bad_form 2 "--set: expects KEY=VALUE" info scenes/cornell.json --set gather)
# --set reaches the scene's settings through the scene file's own reader.
ag_cli_test(info_set 0 "\"texels_per_frame\": 40" info scenes/cornell.json --settings
            --set gather.texels_per_frame=40 --set seed=7)
ag_cli_test(info_set_before_scene 0 "\"seed\": 7" info --set seed=7 scenes/cornell.json --settings)
ag_cli_test(info_set_enum 0 "\"backend\": \"cpu\"" info scenes/cornell.json --settings
            --set gather.backend=cpu)
# Values inline (--frames=2, -n=2) or separate, options before or after the scene.
ag_cli_test(photons_short_inline 0 "frames 2 in" photons -n=2 -q scenes/cornell.json)
ag_cli_test(photons_long_inline 0 "frames 3 in" photons --frames=3 scenes/cornell.json -q)

# Folder boundaries: cpu/ without GL, gpu/ without Embree/FLANN, shared/ without either side.
add_test(NAME boundaries COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/boundaries.sh ${PROJECT_SOURCE_DIR})
set_tests_properties(boundaries PROPERTIES LABELS unit)
# bench settle: SCENE:SCRIPT pairs and --size N or WxH, checked before any GL or reference work.
ag_cli_test(bench_settle_bad_entry 2 "bench settle: expected SCENE:SCRIPT, got 'foo'" bench settle foo)
ag_cli_test(bench_settle_bad_size 2 "--size: expects N or WxH with positive integers up to 16384, got '0x5'"
            bench settle --size 0x5)
# Scripts must be regular files of bounded size, whether named by --script or by the scene.
ag_cli_test(render_script_directory 1 "scenes: a script must be a regular file" render
            scenes/cornell.json --script scenes -o ${CMAKE_CURRENT_BINARY_DIR}/never_written.exr)
ag_cli_test(render_script_dev_zero 1 "/dev/zero: a script must be a regular file" render
            scenes/cornell.json --script /dev/zero -o ${CMAKE_CURRENT_BINARY_DIR}/never_written.exr)
ag_test_timeout(cli.render_script_dev_zero 20)
# --set is checked against the scene as loading checks it: the photon budget, the light samples
# and the lightmap atlas (before anything is allocated), exit 2 naming --set, the setting and the
# limit.
ag_cli_test(info_set_photon_budget 2
            "--set: .*groups \\(100000\\) × photons_per_group \\(100000\\) × lights \\(1\\) = 10000000000 photons; expected at most 100000000"
            info scenes/cornell.json --set photons.groups=100000 --set photons.photons_per_group=100000
            --set photons.refine_layers=1)
ag_cli_test(info_set_caustic_budget 2 "--set: .*caustics/photons.*expected at most 100000000"
            info scenes/two_rooms.json --set caustics.photons=100000000)
ag_cli_test(info_set_atlas 2
            "--set: .*settings.lightmap.texel_size: a texel size of 0.01 makes a lightmap atlas of [0-9]+ texels; expected at most 16777216"
            info scenes/cornell.json --set lightmap.texel_size=0.01)
# The same with finer texels at contacts (tiles and subdivision): refused as it is, before any
# tile grid is made (it took 28 s and named a chart's width instead).
ag_cli_test(info_set_atlas_tiled 2
            "--set: .*settings.lightmap.texel_size: a texel size of 0.01 makes a lightmap atlas of [0-9]+ texels; expected at most 16777216"
            info scenes/cornell.json --set lightmap.texel_size=0.01 --set lightmap.refine_factor=4
            --set lightmap.refine_budget=10 --set lightmap.refine_tile=1
            --set lightmap.refine_reach=1)
# bench soak: the scene's change log holds at most one frame's edits however long the run (two
# objects moved and a light recoloured per frame: 3), where it used to grow by 3 a frame (600
# entries by the end of this run).
add_test(NAME cli.bench_soak_change_log
         COMMAND ${AG_EXPECT} 0 "change log: 0 entries after the last frame, at most 3 before a frame"
                 ${AG_BIN} bench soak scenes/cornell.json --frames 200 --size 64
                 --csv ${CMAKE_CURRENT_BINARY_DIR}/bench-soak-test.csv --set threads=1
                 --set photons.retrace_budget=400 --set caustics.photons=1000
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.bench_soak_change_log PROPERTIES LABELS gl)
# bench frame reports each mode's mean frame time and its p95 (issue #12: the default's frame time
# against the old, mean and p95); the CPU gather and 64² keep it to a few seconds.
add_test(NAME cli.bench_frame_p95
         COMMAND ${AG_EXPECT} 0
                 "static: [0-9.]+ fps \\([0-9.]+ ms/frame, p95 [0-9.]+ ms\\).*gather backend cpu"
                 ${AG_BIN} bench frame scenes/cornell.json --size 64 --frames 3 --repeat 1
                 --gather cpu --set caustics.photons=1000
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.bench_frame_p95 PROPERTIES LABELS gl)
# bench's own --size N|WxH is read digit by digit too: 4294967360 = 2^32 + 64 used to wrap to 64.
foreach(size IN ITEMS 4294967360 64x4294967328 0 5x 5x5x5 x5)
  ag_cli_test(bench_soak_bad_size_${size} 2
              "--size: expects N or WxH with positive integers up to 16384, got '${size}'"
              bench soak --size ${size})
endforeach()
# compare --ldr: the 8-bit metrics of Jimenez Kwast (2016); an image against itself is perfect.
ag_cli_test(compare_ldr_identical 0 "mssim   1.0000" compare --ldr docs/images/sponza.png
            docs/images/sponza.png)
ag_cli_test(compare_ldr_json 0 "\"mse\":0.0" compare --ldr --json docs/images/sponza.png
            docs/images/sponza.png)
# bench gpu_pm: its lists are checked before a GL context is made.
ag_cli_test(bench_gpu_pm_bad_paths 2 "--paths: expects positive numbers separated by commas"
            bench gpu_pm --paths 1,x)
ag_cli_test(bench_gpu_pm_bad_radii 2 "--radii: expects positive numbers" bench gpu_pm --radii 0)
ag_cli_test(bench_gpu_pm_reference_without_frame 2 "--no-direct has none"
            bench gpu_pm --no-direct --reference x.exr)

# Irradiance cache (Gautron 2006, docs/irradiance_cache.md): the bench's three variants run on a
# few tiny frames of Cube in a Box; a bad rc setting names its key.
add_test(NAME cli.bench_irradiance_cache
         COMMAND ${AG_EXPECT} 0 "forever +[0-9]+ +[0-9]+" ${AG_BIN} bench
                 irradiance_cache --frames 6 --size 24x24 --ref-spp 1 --threads 1
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.bench_irradiance_cache PROPERTIES LABELS gl)
# Table 4.2's stand-in: the CPU cache in Radiance's manner and the GL splat interpolate the same
# records to under 1% relative RMS (fails if the octree misses records or the two disagree), and
# AIM records are refused with the setting to use.
add_test(NAME cli.bench_irradiance_cache_versus_cpu
         COMMAND ${AG_EXPECT} 0 "GL records vs GL splat 0[.]00[0-9]" ${AG_BIN} bench
                 irradiance_cache --versus-cpu --size 24x24
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(cli.bench_irradiance_cache_versus_cpu PROPERTIES LABELS gl)
ag_cli_test(bench_irradiance_cache_versus_cpu_aim 2 "add --set rc.source=direct" bench
            irradiance_cache scenes/cornell.json --versus-cpu --size 8x8)
ag_cli_test(rc_bad_source 2 "rc/source: expected one of aim, direct" render scenes/cornell.json -o x.exr
            --set rc.source=glossy)
# Participating media (docs/media.md): pm refuses media; the media method needs media and a
# light, and renders a small grid in a second or two.
ag_cli_test(reference_pm_media 2 "has participating media, which pm does not render"
            reference scenes/media_point_fog.json -m pm -o media_pm.exr)
ag_cli_test(media_no_media 1 "the media method needs media or glass"
            media scenes/two_rooms.json -o media_none.exr --size 8x8)
ag_cli_test(media_no_light 1 "needs an enabled point, spot or quad light"
            media scenes/media_slab.json -o media_quad.exr --size 8x8)
ag_cli_test(media_point_fog 0 "photon marching [0-9.]+ ms"
            media scenes/media_point_fog.json -o ${CMAKE_CURRENT_BINARY_DIR}/media_fog.exr
            --size 16x16 --grid 16 --photons 4000 --slices)
# The adaptive pipeline runs its passes (and writes the level slice); it needs a point light.
ag_cli_test(media_adaptive 0 "adaptive, [0-9]+ pilots marched; pilot generation"
            media scenes/media_glass_fog_point.json
            -o ${CMAKE_CURRENT_BINARY_DIR}/media_adaptive.exr --size 16x16 --grid 16
            --photons 4000 --adaptive --pilots 16 --slices)
ag_cli_test(media_adaptive_quad 1 "the adaptive media pipeline needs a point or spot light"
            media scenes/media_glass_fog.json -o media_adaptive_quad.exr --size 8x8 --grid 8
            --adaptive)

# Renderer robustness (docs/robustness.md, "Renderer sweep"): extreme but valid scenes through
# every indirect method, the references, converge and media at 16x16; fails on a crash, a run
# over its time limit, a NaN or infinite pixel in any image, or a valid scene refused. The CI
# selection runs each case once, the methods in turn (73 runs, 41-67 s on 2 loaded cores);
# every case through every method is labelled slow; --mode full runs everything.
if(AG_PYTHON)
  set(ag_robust_python ${AG_PYTHON})
else()
  set(ag_robust_python python3)
endif()
# Each run's own limit (running time): the sweep's default of 120 s, scaled like the CTest limits.
math(EXPR ag_robust_run_limit "120 * ${AG_TEST_TIME_SCALE}")
# Under the sanitizers the CI selection runs every second case of each run (61 of 115, every run
# kept at least once; the Release suite runs all 115): it took 108 s of CI's 2 cores there, most of
# it starting `afterglow compare` under ASan to check each image (docs/robustness.md,
# "Session 16").
set(ag_robust_ci_share "")
if(AG_SANITIZE)
  set(ag_robust_ci_share --every 2)
endif()
foreach(mode ci methods)
  set(share "")
  if(mode STREQUAL "ci")
    set(share ${ag_robust_ci_share})
  endif()
  add_test(NAME cli.robustness_sweep_${mode}
           COMMAND ${ag_robust_python} ${PROJECT_SOURCE_DIR}/tools/robustness_sweep.py
                   --afterglow ${AG_BIN} --mode ${mode} ${share} -j 2
                   --timeout ${ag_robust_run_limit}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(cli.robustness_sweep_${mode} PROPERTIES SKIP_RETURN_CODE 77 PROCESSORS 2)
endforeach()
set_tests_properties(cli.robustness_sweep_ci PROPERTIES LABELS gl)
set_tests_properties(cli.robustness_sweep_methods PROPERTIES LABELS slow)
ag_test_timeout(cli.robustness_sweep_ci 900)
ag_test_timeout(cli.robustness_sweep_methods 1800)
