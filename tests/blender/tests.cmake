# Blender integration tests (tests/blender/test_*.py), one Blender process each.
#
# Include from the root CMakeLists.txt after the target that fills
# ${CMAKE_BINARY_DIR}/blender_scripts/addons/deferred_render (add-on + native module):
#
#   find_program(BLENDER_EXECUTABLE blender)
#   if(BLENDER_EXECUTABLE)
#     include(${CMAKE_SOURCE_DIR}/tests/blender/tests.cmake)
#   endif()
#
# Needs python3-openimageio (EXR reading inside Blender's Python) and Cycles
# (the factory add-on) for the comparisons. Every test uses the GL stack, so
# they share one RESOURCE_LOCK and run one at a time even under ctest -j.
# All together take about 1.5 minutes on 2 cores with llvmpipe.

set(DEFERRED_BLENDER_SCRIPTS "${CMAKE_BINARY_DIR}/blender_scripts")
set(DEFERRED_BLENDER_TEST_OUT "${CMAKE_BINARY_DIR}/test_out/blender")
set(DEFERRED_BLENDER_FILE "${CMAKE_SOURCE_DIR}/blend_samples/analytic.blend")

set(DEFERRED_BLENDER_TESTS
    export
    registration
    analytic_passes
    samples
    compositor
    animation
    film_view_layers
    border
    alignment_cycles
    bad_scenes
    memory
    light_culling
    world_ao
    node_materials
    node_probes
    emissive
    shadow_terminator
    transparency
    bump_lighting
    world_map
    sky_models
    cryptomatte
    holdout
    aovs
    light_groups
    vector_pass
    motion_blur
    shadow_catcher
    glossy_highlights
    glass
    displacement_bump
    capture_replay
    tangents
    visibility_buffer
)

foreach(_name IN LISTS DEFERRED_BLENDER_TESTS)
  add_test(NAME blender_${_name}
           COMMAND ${BLENDER_EXECUTABLE} -b --factory-startup ${DEFERRED_BLENDER_FILE}
                   --addons deferred_render -E DEFERRED_RENDER
                   --python-exit-code 1
                   --python ${CMAKE_SOURCE_DIR}/tests/blender/test_${_name}.py
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
endforeach()

# The add-on without its native module: enabled by the script itself, not --addons.
add_test(NAME blender_native_missing
         COMMAND ${BLENDER_EXECUTABLE} -b --factory-startup ${DEFERRED_BLENDER_FILE}
                 --python-exit-code 1
                 --python ${CMAKE_SOURCE_DIR}/tests/blender/test_native_missing.py
         WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})

# Blender's real UI under Xvfb (not -b): the engine's panels drawn by the
# Properties editor (tests/blender/gui_panels.py).
find_program(XVFB_RUN xvfb-run)
set(_deferred_blender_gui)
if(XVFB_RUN)
  add_test(NAME blender_gui_panels
           COMMAND ${XVFB_RUN} -a ${BLENDER_EXECUTABLE} --factory-startup --addons deferred_render
                   --python ${CMAKE_SOURCE_DIR}/tests/blender/gui_panels.py
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  # The Rendered viewport (tests/blender/gui_viewport.py): accumulation
  # against final renders, incremental updates, preview thumbnails.
  add_test(NAME blender_gui_viewport
           COMMAND ${XVFB_RUN} -a -s "-screen 0 1024x768x24" ${BLENDER_EXECUTABLE} --factory-startup
                   ${CMAKE_SOURCE_DIR}/blend_samples/analytic.blend --addons deferred_render
                   --python ${CMAKE_SOURCE_DIR}/tests/blender/gui_viewport.py
           WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set(_deferred_blender_gui gui_panels gui_viewport)
else()
  message(WARNING "xvfb-run not found: the Blender GUI tests are not registered (Debian: xvfb xauth)")
endif()

# The export benchmark (tests/blender/bench_export.py) is a script, not a
# test: speed targets live in benchmarks (see README).

set(_deferred_blender_all ${DEFERRED_BLENDER_TESTS} native_missing ${_deferred_blender_gui})
list(TRANSFORM _deferred_blender_all PREPEND "blender_")
set_tests_properties(${_deferred_blender_all} PROPERTIES
    ENVIRONMENT "BLENDER_USER_SCRIPTS=${DEFERRED_BLENDER_SCRIPTS};DEFERRED_TEST_OUT=${DEFERRED_BLENDER_TEST_OUT}"
    TIMEOUT 600
    RESOURCE_LOCK deferred_gl
    LABELS blender)
