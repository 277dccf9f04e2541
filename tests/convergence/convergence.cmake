# Convergence over time (label convergence): selective against brute force on the Cornell scene.
add_test(NAME convergence.cornell_move_cube
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/convergence_test.sh $<TARGET_FILE:afterglow>
                 ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.cornell_move_cube PROPERTIES LABELS convergence SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.cornell_move_cube 600)

# Scheduling by time (DESIGN.md): after the cube jumps, selective settles in no more frames than
# full-budget at the same frame-time target (frames counted, not time).
add_test(NAME convergence.cornell_cube_jump_settle
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/settle_test.sh $<TARGET_FILE:afterglow>
                 ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.cornell_cube_jump_settle PROPERTIES LABELS convergence
                     SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.cornell_cube_jump_settle 300)

# Issue #14: McGuire's Cornell box with its own emissive light, progressive against pt
# (relMSE <= 0.02); skipped without ../shared/external-scenes.
add_test(NAME convergence.cornell_mcguire_pt
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/mcguire_test.sh $<TARGET_FILE:afterglow>
                 ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.cornell_mcguire_pt PROPERTIES LABELS convergence
                     SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.cornell_mcguire_pt 300)

# Issue #14: an emissive mesh's direct light, its samples moved over frames, converges to pt's.
add_test(NAME convergence.mesh_light_direct_pt
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/mesh_light_direct_test.sh
                 $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.mesh_light_direct_pt PROPERTIES LABELS convergence
                     SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.mesh_light_direct_pt 120)

# Issue #14: gpu_pm's photons bounce with the texel's albedo on textured surfaces.
add_test(NAME convergence.gpu_pm_textured_pt
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/gpu_pm_textured_test.sh
                 $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.gpu_pm_textured_pt PROPERTIES LABELS convergence
                     SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.gpu_pm_textured_pt 120)
# Issue #20: every indirect method through the same edits at 48x48, each held to its settled error
# and to the frames it takes to settle after the last edit (tests/convergence/check_compare_methods.py).
add_test(NAME convergence.compare_methods
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/compare_methods_test.sh
                 $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.compare_methods PROPERTIES LABELS convergence SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.compare_methods 300)
# Issue #18: converge --reference-frames scores chosen frames against references of their own
# states (the ghosting check of temporal caching).
add_test(NAME convergence.reference_frames
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/convergence/reference_frames_test.sh
                 $<TARGET_FILE:afterglow> ${PROJECT_BINARY_DIR}/convergence
         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
set_tests_properties(convergence.reference_frames PROPERTIES LABELS convergence SKIP_RETURN_CODE 77)
ag_test_timeout(convergence.reference_frames 120)
