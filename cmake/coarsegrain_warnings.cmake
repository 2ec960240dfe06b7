# Warnings for our own targets only (PRIVATE), never for dependencies.
function(coarsegrain_warnings target)
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wno-unused-parameter)
endfunction()
