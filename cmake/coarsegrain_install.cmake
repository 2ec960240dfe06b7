# Install rules (included by the top-level CMakeLists.txt when COARSEGRAIN_INSTALL is on):
#   cmake --install build/release --prefix P
# puts the command-line tool in P/bin, the library in P/lib, the public headers in
# P/include/coarsegrain, the plotting scripts the tool runs in P/share/coarsegrain/scripts and
# the CMake package in P/lib/cmake/coarsegrain, for find_package(coarsegrain) and the target
# coarsegrain::coarsegrain.
#
# The library is static (the default; BUILD_SHARED_LIBS=ON builds a shared one): a consumer
# links its private dependencies too, so the exported target lists them as
# $<LINK_ONLY:CHOLMOD::CHOLMOD>, $<LINK_ONLY:UMFPACK::UMFPACK> and $<LINK_ONLY:LAPACK::LAPACK>
# (CMake does this for every PRIVATE dependency of a static library), and coarsegrainConfig.cmake
# finds them, CHOLMOD and UMFPACK with the Find modules installed beside it.
include(CMakePackageConfigHelpers)

set(COARSEGRAIN_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/coarsegrain)

install(TARGETS coarsegrain EXPORT coarsegrainTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS coarsegrain_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/coarsegrain
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
file(GLOB COARSEGRAIN_PLOT_SCRIPTS CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/scripts/plot_*.py)
install(FILES ${COARSEGRAIN_PLOT_SCRIPTS} DESTINATION ${COARSEGRAIN_INSTALL_SCRIPTSDIR})

install(EXPORT coarsegrainTargets NAMESPACE coarsegrain::
        DESTINATION ${COARSEGRAIN_INSTALL_CMAKEDIR})
get_target_property(COARSEGRAIN_LIBRARY_TYPE coarsegrain TYPE)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/coarsegrainConfig.cmake.in
    ${PROJECT_BINARY_DIR}/coarsegrainConfig.cmake
    INSTALL_DESTINATION ${COARSEGRAIN_INSTALL_CMAKEDIR})
# 0.x: a minor version may break the API.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/coarsegrainConfigVersion.cmake
    COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/coarsegrainConfig.cmake
              ${PROJECT_BINARY_DIR}/coarsegrainConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindUMFPACK.cmake
        DESTINATION ${COARSEGRAIN_INSTALL_CMAKEDIR})
