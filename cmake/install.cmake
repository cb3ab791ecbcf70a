# `cmake --install`: the libraries, their headers and a CMake package (granuflowConfig.cmake, its version file and the
# exported targets), so that another project can find_package(granuflow) and build units or kernels against it.
include(CMakePackageConfigHelpers)

set(GRANUFLOW_LIBRARIES granuflow_framework granuflow_kernels granuflow_units granuflow_calibration)
set_target_properties(granuflow_framework PROPERTIES EXPORT_NAME framework)
set_target_properties(granuflow_kernels PROPERTIES EXPORT_NAME kernels)
set_target_properties(granuflow_units PROPERTIES EXPORT_NAME units)
set_target_properties(granuflow_calibration PROPERTIES EXPORT_NAME calibration)
install(TARGETS ${GRANUFLOW_LIBRARIES} EXPORT granuflowTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# Headers keep the paths the sources include them by: granuflow/*.hpp, kernels/..., units/...
install(DIRECTORY framework/include/granuflow framework/calibration/include/granuflow
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
install(FILES ${GRANUFLOW_GENERATED_INCLUDE}/granuflow/version.hpp DESTINATION ${GRANUFLOW_INSTALL_INCLUDEDIR})
install(DIRECTORY kernels units DESTINATION ${GRANUFLOW_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")

set(GRANUFLOW_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/granuflow)
install(EXPORT granuflowTargets NAMESPACE granuflow:: DESTINATION ${GRANUFLOW_CMAKE_DIR})
configure_package_config_file(cmake/granuflowConfig.cmake.in ${CMAKE_BINARY_DIR}/granuflowConfig.cmake
                              INSTALL_DESTINATION ${GRANUFLOW_CMAKE_DIR})
# A plugin is tied to the version it was built against (granuflow refuses another at load), so only the exact
# version is compatible.
write_basic_package_version_file(${CMAKE_BINARY_DIR}/granuflowConfigVersion.cmake COMPATIBILITY ExactVersion)
install(FILES ${CMAKE_BINARY_DIR}/granuflowConfig.cmake ${CMAKE_BINARY_DIR}/granuflowConfigVersion.cmake
              cmake/granuflowPlugin.cmake DESTINATION ${GRANUFLOW_CMAKE_DIR})
