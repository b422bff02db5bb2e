// Accelerator agreement on real scene files: candela's own and (when present) the CS184 ones.
#include "../support/cs184.h"
#include "candela/diagnostics/check.h"
#include "candela/io/collada.h"
#include "candela/scene/builder.h"

#include <catch2/catch.hpp>

#include <string>
#include <vector>

using namespace candela;

namespace {

void check_backends_agree(const std::vector<std::string>& paths) {
    for (const std::string& name : paths) {
        Diagnostics diag;
        const Scene scene = load_scene(name, BuildOptions{}, diag);
        CheckOptions opt;
        opt.camera_width = 160;
        opt.camera_height = 120;
        opt.bounce_rays = 20000;
        opt.shadow_rays = 20000;
        opt.edge_rays = 10000;
        opt.seed = 3;
        // Brute runs only on the small scenes, where it costs well under a second.
        opt.brute_max_tests = 5e8;
        for (TriangleTest test : {TriangleTest::MollerTrumbore, TriangleTest::Watertight}) {
            opt.triangle = test;
            const CheckReport rep = run_check(scene, opt);
            INFO(name << " triangle test " << static_cast<int>(test) << "\n" << rep.to_text());
            REQUIRE(rep.triangles > 0);
            CHECK(rep.ok());
            for (const CheckPair& p : rep.pairs) {
                std::uint64_t n = 0, same = 0;
                for (int k = 0; k < kCheckRayKindCount; ++k) {
                    const auto& row = p.counts[k];
                    CHECK(row[static_cast<int>(HitClass::Leak)] == 0);
                    if (static_cast<CheckRayKind>(k) == CheckRayKind::Edge) continue;
                    for (std::uint64_t v : row)
                        n += v;
                    same += row[static_cast<int>(HitClass::Agree)] +
                            row[static_cast<int>(HitClass::Tie)];
                }
                CHECK(n > 50000);
                CHECK(static_cast<double>(same) >= 0.9999 * static_cast<double>(n));
                if (p.reference == "brute" && p.other == "builtin") {
                    // Same arithmetic on the same vertices: only ties may differ.
                    std::uint64_t ties = 0;
                    for (const auto& row : p.counts)
                        ties += row[static_cast<int>(HitClass::Tie)];
                    CHECK(p.disagreements() == ties);
                }
            }
        }
    }
}

} // namespace

TEST_CASE("backends agree on the CS184 scenes", "[accel][slow]") {
    CANDELA_SKIP_WITHOUT_CS184();
    std::vector<std::string> paths;
    for (const char* name :
         {"CBspheres_lambertian.dae", "CBgems.dae", "CBbunny.dae", "bunny.dae", "cow.dae"})
        paths.push_back(test::cs184_scene(name));
    check_backends_agree(paths);
}

TEST_CASE("backends agree on the own scenes", "[accel][slow]") {
    std::vector<std::string> paths;
    for (const char* name : {"cornell-box.dae", "cornell-spheres.dae", "glass.dae", "glossy.dae",
                             "lights.dae", "materials.dae"})
        paths.push_back(test::project_scene(name));
    check_backends_agree(paths);
}
