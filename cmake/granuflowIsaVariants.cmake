# Run-time choice of the instruction set without code of ours: glibc (>= 2.33) looks for a library first in the
# subfolders glibc-hwcaps/x86-64-v4, -v3 and -v2 of every folder it searches (RUNPATH included) and loads the most
# capable copy this CPU can run (`ld.so --help` lists them). granuflow_add_isa_variants(TARGET) builds the shared
# library TARGET once more for each level of GRANUFLOW_ISA_VARIANTS, from the same sources, with the same file name
# and SONAME, into <build>/isa/<level>/, and installs it into <libdir>/glibc-hwcaps/<level>/ beside the baseline copy
# in <libdir> (docs/install_and_plugins.md, "Portable builds").
#
# Call it in the folder that made TARGET, after its last target_* command: the copy takes the target's properties
# as they are then, and the source files' properties (set_source_files_properties) hold per folder.
set(GRANUFLOW_ISA_VARIANTS "" CACHE STRING "x86-64 levels (e.g. x86-64-v3) of extra copies of the core libraries")
foreach(isa IN LISTS GRANUFLOW_ISA_VARIANTS)
  if(NOT isa MATCHES "^x86-64-v[234]$")
    message(FATAL_ERROR "GRANUFLOW_ISA_VARIANTS: '${isa}' is not a level glibc's loader selects "
                        "(glibc-hwcaps): x86-64-v2, x86-64-v3 or x86-64-v4")
  endif()
endforeach()

# The instruction set a target is compiled for, as build_info() reports it (target property GRANUFLOW_ISA).
define_property(TARGET PROPERTY GRANUFLOW_ISA BRIEF_DOCS "instruction set the target is compiled for"
                FULL_DOCS "x86-64, x86-64-v3, ... or native; compiled into granuflow::build_info()")

function(granuflow_add_isa_variants target)
  get_target_property(name ${target} OUTPUT_NAME)
  if(NOT name)
    set(name ${target})
  endif()
  get_target_property(type ${target} TYPE)
  if(GRANUFLOW_ISA_VARIANTS AND NOT type STREQUAL "SHARED_LIBRARY")
    message(FATAL_ERROR "GRANUFLOW_ISA_VARIANTS: ${target} is a ${type}; the loader picks copies of shared libraries "
                        "only (BUILD_SHARED_LIBS=ON)")
  endif()
  get_target_property(sources ${target} SOURCES)
  foreach(isa IN LISTS GRANUFLOW_ISA_VARIANTS)
    string(MAKE_C_IDENTIFIER "${target}_${isa}" variant)
    add_library(${variant} SHARED ${sources})
    foreach(prop INCLUDE_DIRECTORIES COMPILE_DEFINITIONS COMPILE_OPTIONS COMPILE_FEATURES LINK_LIBRARIES LINK_OPTIONS
                 VERSION SOVERSION)
      get_target_property(value ${target} ${prop})
      if(value)
        set_property(TARGET ${variant} PROPERTY ${prop} "${value}")
      endif()
    endforeach()
    target_compile_options(${variant} PRIVATE -march=${isa})
    # Eigen aligns its fixed-size objects (and with them the AD numbers the libraries, the Python module and plugins
    # exchange) to the vector width: 16 bytes at the baseline, 32 with AVX. Held at the baseline's 16, a copy for a
    # wider instruction set keeps the baseline's layout, so either copy works with the same extension and plugins
    # (Eigen still uses the wide vectors, with unaligned loads).
    target_compile_definitions(${variant} PRIVATE EIGEN_MAX_ALIGN_BYTES=16)
    # The copy's own dependencies (the other core libraries) are searched for from <libdir>, like the baseline's, so
    # that the loader picks their variant by the same rule.
    set_target_properties(${variant} PROPERTIES OUTPUT_NAME ${name} GRANUFLOW_ISA ${isa}
                          LIBRARY_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/isa/${isa} INSTALL_RPATH "$ORIGIN/../..")
    install(TARGETS ${variant} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/glibc-hwcaps/${isa})
  endforeach()
endfunction()
