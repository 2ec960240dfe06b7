// libFuzzer target for the scene loader: every input either loads or throws coarsegrain::Error;
// any other exception, a crash, a sanitizer report, a hang or a memory blow-up is a bug.
#include <cstdint>
#include <filesystem>

#include "coarsegrain/common/error.hpp"
#include "load_fuzz_scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    // Relative mesh and material files resolve against the test meshes of the source tree, so
    // that an input naming one of them (the seed scene_mesh_file.json does) reads a real file.
    static const std::string base = COARSEGRAIN_FUZZ_BASE_DIR;
    try {
        coarsegrain::fuzz::load_fuzz_scene(data, size, base);
    } catch (const coarsegrain::Error&) {
        // Bad input reported as it should be.
    }
    return 0;
}
