# Installs this build into BUILD/plugin-example/prefix (cmake --install) and builds examples/plugin against that
# installed package (find_package(granuflow)) in BUILD/plugin-example/build, as a user's own project would be; the
# example's scene is copied beside it, where its relative `plugins:` path finds the library.
#   cmake -DBUILD=<granuflow build dir> -DSOURCE=<repository> [-DLAUNCHER=ccache] -P build_plugin_example.cmake
# Both steps are incremental: a second call costs a few seconds. Used by the ctest plugin.example_build and by
# tests/python/test_plugins.py.
set(root ${BUILD}/plugin-example)
file(COPY ${SOURCE}/examples/plugin/example_scene.yaml DESTINATION ${root})
execute_process(COMMAND ${CMAKE_COMMAND} --install ${BUILD} --prefix ${root}/prefix OUTPUT_QUIET
                RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "cmake --install ${BUILD} failed (${rc})")
endif()
set(args -S ${SOURCE}/examples/plugin -B ${root}/build -G Ninja -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${root}/prefix)
if(LAUNCHER)
  list(APPEND args -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
execute_process(COMMAND ${CMAKE_COMMAND} ${args} OUTPUT_QUIET RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "configuring examples/plugin against ${root}/prefix failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${root}/build RESULT_VARIABLE rc)
if(rc)
  message(FATAL_ERROR "building examples/plugin failed (${rc})")
endif()
