# Finds SuiteSparse CHOLMOD. Debian 12 ships SuiteSparse 5.12 without CMake package files, so
# this module locates the header and libraries itself and defines the imported target
# CHOLMOD::CHOLMOD (used through Eigen's CholmodSupport).
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
find_library(SUITESPARSE_CONFIG_LIBRARY suitesparseconfig)
foreach(lib amd camd colamd ccolamd)
    string(TOUPPER ${lib} LIB)
    find_library(${LIB}_LIBRARY ${lib})
endforeach()
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CHOLMOD REQUIRED_VARS CHOLMOD_LIBRARY CHOLMOD_INCLUDE_DIR
                                  SUITESPARSE_CONFIG_LIBRARY)
if(CHOLMOD_FOUND AND NOT TARGET CHOLMOD::CHOLMOD)
    add_library(CHOLMOD::CHOLMOD UNKNOWN IMPORTED)
    set_target_properties(CHOLMOD::CHOLMOD PROPERTIES
        IMPORTED_LOCATION "${CHOLMOD_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${CHOLMOD_INCLUDE_DIR}")
    set(_deps ${SUITESPARSE_CONFIG_LIBRARY})
    foreach(LIB AMD CAMD COLAMD CCOLAMD)
        if(${LIB}_LIBRARY)
            list(APPEND _deps ${${LIB}_LIBRARY})
        endif()
    endforeach()
    set_property(TARGET CHOLMOD::CHOLMOD PROPERTY INTERFACE_LINK_LIBRARIES "${_deps}")
endif()
