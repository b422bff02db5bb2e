// Fuzzing regression corpus (tests/data/fuzz/, see docs/fuzzing.md): every input the fuzzer
// found a bug with must now load and build, or be rejected with candela::Error, quickly. Any
// other exception fails the test; a crash or hang fails the run.
#include "candela/io/collada.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/stopwatch.h"

#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

using namespace candela;

namespace {

/// The regression inputs are at most a few KB; each loads in well under 10 ms in a release
/// build. 2 s allows for a debug or sanitizer build while still catching the quadratic or
/// runaway behaviour that some of the findings were about.
constexpr double kMaxSecondsPerInput = 2.0;

} // namespace

TEST_CASE("fuzz regression: every input loads or fails with candela::Error",
          "[fuzz-regression][quick]") {
    namespace fs = std::filesystem;
    const fs::path dir = fs::path(CANDELA_TEST_DATA) / "fuzz";
    std::vector<fs::path> inputs;
    for (const auto& entry : fs::directory_iterator(dir))
        if (entry.is_regular_file() && entry.path().filename() != "README.md")
            inputs.push_back(entry.path());
    std::sort(inputs.begin(), inputs.end());
    REQUIRE(!inputs.empty());

    int loaded = 0, rejected = 0;
    for (const fs::path& path : inputs) {
        INFO(path.filename().string());
        const Stopwatch timer;
        Diagnostics diag;
        try {
            SceneDesc desc = load_collada(path.string(), diag);
            for (CameraMode mode : {CameraMode::Framed, CameraMode::File}) {
                BuildOptions opt;
                opt.camera_mode = mode;
                Scene scene = build_scene(desc, opt, diag);
                (void)scene;
            }
            ++loaded;
        } catch (const Error& e) {
            // A rejection must say where: the file, and its line when there is one.
            const std::string msg = e.what();
            INFO(msg);
            REQUIRE(e.where());
            CHECK(e.where()->file == path.string());
            CHECK(msg.rfind(path.string(), 0) == 0);
            CHECK(!e.message().empty());
            ++rejected;
        }
        const double seconds = timer.seconds();
        CHECK(seconds < kMaxSecondsPerInput);
    }
    CHECK(loaded + rejected == static_cast<int>(inputs.size()));
}
