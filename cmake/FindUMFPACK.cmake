# Finds SuiteSparse UMFPACK (sparse LU; Debian 12's SuiteSparse 5.12 has no CMake package files)
# and defines the imported target UMFPACK::UMFPACK (used through Eigen's UmfPackSupport). Needs
# CHOLMOD::CHOLMOD (FindCHOLMOD.cmake), which UMFPACK links against.
find_path(UMFPACK_INCLUDE_DIR umfpack.h PATH_SUFFIXES suitesparse)
find_library(UMFPACK_LIBRARY umfpack)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(UMFPACK REQUIRED_VARS UMFPACK_LIBRARY UMFPACK_INCLUDE_DIR)
if(UMFPACK_FOUND AND NOT TARGET UMFPACK::UMFPACK)
    add_library(UMFPACK::UMFPACK UNKNOWN IMPORTED)
    set_target_properties(UMFPACK::UMFPACK PROPERTIES
        IMPORTED_LOCATION "${UMFPACK_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${UMFPACK_INCLUDE_DIR}"
        INTERFACE_LINK_LIBRARIES CHOLMOD::CHOLMOD)
endif()
