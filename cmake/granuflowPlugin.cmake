# granuflow_add_plugin(NAME SOURCES...): a shared library of units and kernels that granuflow loads at run time
# (a scene's `plugins:` list or GRANUFLOW_PLUGIN_PATH). It links the installed libraries, so the units and kernels it
# registers land in the one registry the granuflow command and the Python module use, and it is compiled with the
# options granuflow's own code is compiled with (C++17, no contraction into fused multiply-adds).
function(granuflow_add_plugin name)
  add_library(${name} MODULE ${ARGN})
  target_link_libraries(${name} PRIVATE granuflow::units granuflow::kernels granuflow::framework)
  target_compile_features(${name} PRIVATE cxx_std_17)
  target_compile_options(${name} PRIVATE -ffp-contract=off -fno-math-errno -fopenmp-simd)
  set_target_properties(${name} PROPERTIES PREFIX "lib")
endfunction()
