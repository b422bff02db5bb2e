// libFuzzer target for the scene loader: arbitrary bytes -> parse_collada -> build_scene.
//
// The loader may reject any input, but only by throwing candela::Error. Any other exception,
// a crash, a hang, a leak or a sanitizer report is a finding. Build with tools/fuzz.sh.
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    candela::set_verbose(false);
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    candela::Diagnostics diag;
    try {
        candela::SceneDesc desc = candela::parse_collada(text, "fuzz.dae", diag);
        candela::BuildOptions opt;
        // Both camera modes run different code; pick one from the input so that both are
        // reached without doubling the work per input.
        opt.camera_mode = (size % 2 == 0) ? candela::CameraMode::Framed : candela::CameraMode::File;
        candela::Scene scene = candela::build_scene(desc, opt, diag);
        (void)scene;
    } catch (const candela::Error&) {
        // Rejecting the input with a diagnostic is the expected outcome for most inputs.
    }
    // The Diagnostics destructor prints the collected warnings to stderr; tools/fuzz.sh runs
    // with -close_fd_mask=2 so that they do not slow the campaign down.
    return 0;
}
