// `candela merge`: partial renders with disjoint sample ranges add up to the full render.
#include "candela/io/collada.h"
#include "candela/io/image_io.h"
#include "candela/render/exr_layout.h"
#include "candela/render/merge.h"
#include "candela/render/output.h"
#include "candela/render/renderer.h"
#include "candela/render/setting_table.h"
#include "candela/scene/builder.h"
#include "candela/util/error.h"
#include "candela/util/log.h"
#include "render_compare.h"
#include "render_support.h"

#include <catch2/catch.hpp>

#include <filesystem>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

using namespace candela;
namespace fs = std::filesystem;

namespace {

const std::string kScene = std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae";

/// Runs a program to completion; returns its exit status (-1 when it did not exit normally).
int run_program(const std::string& bin, const std::vector<std::string>& args) {
    std::vector<std::string> copy = args;
    std::vector<char*> argv;
    std::string b = bin;
    argv.push_back(b.data());
    for (auto& a : copy)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, bin.c_str(), nullptr, nullptr, argv.data(), environ) == 0);
    int status = 0;
    REQUIRE(waitpid(pid, &status, 0) == pid);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A render of samples [offset, offset + spp) as the EXR image `candela render` writes.
ImageData render_part(const Scene& scene, RenderSettings s, int offset, int spp) {
    s.sample_offset = std::uint64_t(offset);
    s.spp = spp;
    Film f = test::render_film(scene, s);
    return film_to_image(f, {{"candela:scene", "test"},
                             {"candela:seed", std::to_string(s.seed)},
                             {"candela:spp", std::to_string(spp)},
                             {"candela:sample_offset", std::to_string(offset)},
                             {"candela:samples", std::to_string(f.total_samples())},
                             {"candela:nonfinite_dropped", std::to_string(f.total_dropped())}});
}

/// A render small enough to make many parts of quickly.
RenderSettings tiny_settings() {
    RenderSettings s;
    s.width = 8;
    s.height = 6;
    s.max_depth = 2;
    s.threads = 1;
    s.quiet = true;
    return s;
}

} // namespace

TEST_CASE("merging disjoint sample ranges equals the full render", "[merge][quick]") {
    Diagnostics diag;
    Scene scene = load_scene(kScene, BuildOptions{}, diag);
    RenderSettings s;
    s.width = 24;
    s.height = 18;
    s.max_depth = 3;
    s.threads = 1;
    s.quiet = true;
    s.aovs = AovSet::all();
    s.seed = 7;

    const ImageData full = render_part(scene, s, 0, 16);
    const ImageData a = render_part(scene, s, 0, 5);
    const ImageData b = render_part(scene, s, 5, 11);
    // Order of the inputs does not matter: ranges are sorted by their first index.
    const ImageData merged = merge_images({b, a}, {"b.exr", "a.exr"});
    test::CompareResult r = test::compare_renders(full, merged);
    CHECK(r.count_diffs == 0);
    CHECK(r.max_ratio <= 1.0);
    WARN("merge vs full: max relative RGB difference " << r.max_rgb_rel << ", max error/bound "
                                                       << r.max_ratio);
    CHECK(merged.meta("candela:spp") == "16");
    CHECK(merged.meta("candela:sample_offset") == "0");
    CHECK(merged.meta("candela:merged_ranges") == "[0,5) [5,16)");
    CHECK(merged.meta("candela:samples") == full.meta("candela:samples"));

    // Three parts with a gap are fine too (a part may be missing); the counts say so.
    const ImageData c = render_part(scene, s, 20, 4);
    const ImageData m3 = merge_images({a, b, c}, {"a", "b", "c"});
    CHECK(m3.meta("candela:spp") == "20");
    CHECK(m3.at(3, 3, m3.channel_index("samples")) ==
          full.at(3, 3, full.channel_index("samples")) + c.at(3, 3, c.channel_index("samples")));
}

TEST_CASE("merge lists the sample ranges the parts used, not the ones they were given",
          "[merge][quick]") {
    Diagnostics diag;
    Scene scene = load_scene(kScene, BuildOptions{}, diag);
    const RenderSettings s = tiny_settings();
    // Parts given [0,4) and [16,20) whose metadata says they used [0,9) and [16,23), as parts of
    // the relative sampler (its -s is a budget) record in candela:sample_end.
    ImageData a = render_part(scene, s, 0, 4);
    ImageData b = render_part(scene, s, 16, 4);
    a.set({exr::kSampleEnd, 9});
    b.set({exr::kSampleEnd, 23});
    const ImageData merged = merge_images({b, a}, {"b.exr", "a.exr"});
    CHECK(merged.meta(exr::kMergedRanges) == "[0,9) [16,23)");
    CHECK(merged.meta(exr::kSampleEnd) == "23");
}

TEST_CASE("merge refuses inputs that are not parts of one render", "[merge][quick]") {
    Diagnostics diag;
    Scene scene = load_scene(kScene, BuildOptions{}, diag);
    const RenderSettings s = tiny_settings();
    const ImageData a = render_part(scene, s, 0, 4);
    const ImageData b = render_part(scene, s, 4, 4);

    auto kind_of = [](const auto& fn) {
        try {
            fn();
        } catch (const Error& e) {
            return int(e.kind());
        }
        return 0;
    };
    // Overlapping ranges repeat samples.
    const ImageData overlap = render_part(scene, s, 2, 4);
    CHECK(kind_of([&] { merge_images({a, overlap}, {"a", "o"}); }) == int(ErrorKind::Usage));
    CHECK(kind_of([&] { merge_images({a, a}, {"a", "a2"}); }) == int(ErrorKind::Usage));
    // One input is not a merge.
    CHECK(kind_of([&] { merge_images({a}, {"a"}); }) == int(ErrorKind::Usage));
    // Different seed, size or channels.
    ImageData seed = b;
    seed.set({"candela:seed", "99"});
    CHECK(kind_of([&] { merge_images({a, seed}, {"a", "s"}); }) == int(ErrorKind::Usage));
    RenderSettings s2 = s;
    s2.width = 9;
    CHECK(kind_of([&] {
              merge_images({a, render_part(scene, s2, 4, 4)}, {"a", "w"});
          }) == int(ErrorKind::Usage));
    RenderSettings s3 = s;
    s3.aovs = AovSet::parse("albedo");
    CHECK(kind_of([&] {
              merge_images({a, render_part(scene, s3, 4, 4)}, {"a", "c"});
          }) == int(ErrorKind::Usage));
    // Missing range metadata.
    ImageData bare = b;
    bare.attributes.clear();
    CHECK(kind_of([&] { merge_images({a, bare}, {"a", "bare"}); }) == int(ErrorKind::Usage));
    // The good pair merges.
    CHECK(kind_of([&] { merge_images({a, b}, {"a", "b"}); }) == 0);
}

TEST_CASE("merge reads the noise threshold of files written before it had its own key",
          "[merge][quick]") {
    Diagnostics diag;
    Scene scene = load_scene(kScene, BuildOptions{}, diag);
    const RenderSettings s = tiny_settings();
    // How the render command spells an adaptive sampler's tolerances: before the noise threshold
    // had a key of its own, adaptive_tol held it (relative) or -a's tolerance (cs184).
    auto spelled = [](ImageData img, const char* kind, float tol, const float* threshold) {
        img.set({setting_key(Setting::Adaptive), kind});
        img.set({setting_key(Setting::AdaptiveTol), tol});
        if (threshold) img.set({setting_key(Setting::NoiseThreshold), *threshold});
        return img;
    };
    const float zero = 0.f, two = 0.02f, five = 0.05f;
    const ImageData a = render_part(scene, s, 0, 4), b = render_part(scene, s, 4, 4);
    auto merges = [](const ImageData& x, const ImageData& y) {
        try {
            merge_images({x, y}, {"x", "y"});
        } catch (const Error&) {
            return false;
        }
        return true;
    };
    const ImageData old_relative = spelled(a, "relative", 0.02f, nullptr);
    CHECK(merges(old_relative, spelled(b, "relative", 0.f, &two)));
    CHECK(merges(spelled(b, "relative", 0.f, &two), old_relative));
    CHECK_FALSE(merges(old_relative, spelled(b, "relative", 0.f, &five)));
    const ImageData old_cs184 = spelled(a, "cs184", 0.1f, nullptr);
    CHECK(merges(old_cs184, spelled(b, "cs184", 0.1f, &zero)));
    CHECK_FALSE(merges(old_cs184, spelled(b, "cs184", 0.2f, &zero)));
}

TEST_CASE("candela merge of two half renders equals the full render", "[merge]") {
    fs::path dir = fs::temp_directory_path() / ("candela-merge-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    // Uniform sampling: disjoint sample ranges of an adaptive render are not a split render.
    const std::vector<std::string> common = {"-r", "32", "24",     "-m", "3",          "-t",
                                             "1",  "-q", "--seed", "3",  "--adaptive", "none"};
    auto render = [&](const fs::path& out, std::vector<std::string> extra) {
        std::vector<std::string> args = {"render", kScene, "-f", out.string()};
        args.insert(args.end(), common.begin(), common.end());
        args.insert(args.end(), extra.begin(), extra.end());
        return run_program(CANDELA_BINARY, args);
    };
    const fs::path full = dir / "full.exr", h0 = dir / "h0.exr", h1 = dir / "h1.exr",
                   merged = dir / "merged.exr";
    REQUIRE(render(full, {"-s", "24"}) == 0);
    REQUIRE(render(h0, {"-s", "12", "--sample-offset", "0"}) == 0);
    REQUIRE(render(h1, {"-s", "12", "--sample-offset", "12"}) == 0);
    REQUIRE(run_program(CANDELA_BINARY,
                        {"merge", h0.string(), h1.string(), "-o", merged.string(), "-q"}) == 0);
    const ImageData f = read_image(full.string()), m = read_image(merged.string());
    test::CompareResult r = test::compare_renders(f, m);
    CHECK(r.count_diffs == 0);
    CHECK(r.max_ratio <= 1.0);
    CHECK(m.meta("candela:spp") == "24");
    WARN("candela merge vs full render: max relative RGB difference "
         << r.max_rgb_rel << ", max error/bound " << r.max_ratio);
    // Merging a part with itself is refused and writes nothing.
    const fs::path bad = dir / "bad.exr";
    CHECK(run_program(CANDELA_BINARY, {"merge", h0.string(), h0.string(), "-o", bad.string(),
                                       "-q"}) == int(ErrorKind::Usage));
    CHECK_FALSE(fs::exists(bad));
    fs::remove_all(dir);
}
