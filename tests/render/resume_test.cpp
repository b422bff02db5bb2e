// A render interrupted by a signal leaves a valid image and a checkpoint; resuming it gives an
// image bit-identical to a render that never stopped. Runs the real `candela` executable.
#include "candela/io/image_io.h"

#include <catch2/catch.hpp>

#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

using namespace candela;
namespace fs = std::filesystem;

namespace {

pid_t spawn(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    std::string bin = CANDELA_BINARY;
    argv.push_back(bin.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, bin.c_str(), nullptr, nullptr, argv.data(), environ) == 0);
    return pid;
}

int wait_exit(pid_t pid) {
    int status = 0;
    REQUIRE(waitpid(pid, &status, 0) == pid);
    REQUIRE(WIFEXITED(status));
    return WEXITSTATUS(status);
}

int run(const std::vector<std::string>& args) {
    return wait_exit(spawn(args));
}

/// Waits (bounded) until `path` exists.
bool wait_for_file(const fs::path& path, double seconds) {
    auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (fs::exists(path)) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
}

const std::string kScene = std::string(CANDELA_PROJECT_SCENES) + "/cornell-spheres.dae";
// Uniform passes of one sample (--adaptive none), so that an interrupt lands mid-render.
const std::vector<std::string> kSettings = {"-r", "48",         "36", "-s",         "256",  "-m",
                                            "3",  "--pass-spp", "1",  "--adaptive", "none", "-q"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
}

/// Starts a render, waits for its first checkpoint, interrupts it. Returns the exit status.
int render_and_interrupt(const std::string& scene, const fs::path& out, int signal) {
    pid_t pid =
        spawn(with({"render", scene, "-f", out.string(), "--checkpoint-every", "1e-6"}, kSettings));
    bool started = wait_for_file(out.string() + ".ckpt", 60.0);
    ::kill(pid, signal);
    int status = wait_exit(pid);
    REQUIRE(started);
    return status;
}

} // namespace

TEST_CASE("an interrupted render resumes to a bit-identical image", "[resume][slow]") {
    fs::path dir = fs::temp_directory_path() / ("candela-resume-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path full = dir / "full.exr", part = dir / "part.exr";
    const std::string ckpt = part.string() + ".ckpt";

    REQUIRE(run(with({"render", kScene, "-f", full.string()}, kSettings)) == 0);
    const int signal = GENERATE(SIGINT, SIGTERM);
    CHECK(render_and_interrupt(kScene, part, signal) == 5);

    // The partial image is a valid EXR whose sample counts are the passes it finished.
    ImageData partial = read_image(part.string());
    REQUIRE(fs::exists(ckpt));
    int sc = partial.channel_index("samples");
    REQUIRE(sc >= 0);
    float n0 = partial.at(0, 0, sc);
    CHECK(n0 >= 1.f);
    CHECK(n0 < 256.f);
    bool uniform = true;
    for (int y = 0; y < partial.height; ++y)
        for (int x = 0; x < partial.width; ++x)
            uniform &= partial.at(x, y, sc) == n0;
    CHECK(uniform);
    CHECK(partial.meta("candela:interrupted") == "1");

    SECTION("changed settings are refused") {
        CHECK(run({"render", "--resume", ckpt, "-q", "-s", "128"}) == 2);
        CHECK(run({"render", "--resume", ckpt, "-q", "-m", "4"}) == 2);
        CHECK(fs::exists(ckpt));
    }
    SECTION("resuming completes the render bit-identically") {
        CHECK(run({"render", "--resume", ckpt, "-q", "-t", "1"}) == 0);
        ImageData a = read_image(full.string()), b = read_image(part.string());
        REQUIRE(a.channel_names == b.channel_names);
        REQUIRE(a.pixels.size() == b.pixels.size());
        CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
        CHECK_FALSE(fs::exists(ckpt)); // a finished render removes its checkpoint
    }
    fs::remove_all(dir);
}

TEST_CASE("a kept checkpoint refines a finished render to the direct render's image",
          "[resume][refine][slow]") {
    fs::path dir = fs::temp_directory_path() / ("candela-refine-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path direct = dir / "direct.exr", refined = dir / "refined.exr";
    const std::string ckpt = refined.string() + ".ckpt";
    const std::vector<std::string> settings = {"-r", "48", "36", "-s", "512", "-m", "3", "-q"};
    REQUIRE(run(with({"render", kScene, "-f", direct.string(), "--noise-threshold", "0.02"},
                     settings)) == 0);
    REQUIRE(run(with({"render", kScene, "-f", refined.string(), "--noise-threshold", "0.04",
                      "--keep-checkpoint"},
                     settings)) == 0);
    REQUIRE(fs::exists(ckpt));
    // The same settings again: nothing to refine; a looser threshold: refused.
    CHECK(run({"render", "--resume", ckpt, "-q"}) == 2);
    CHECK(run({"render", "--resume", ckpt, "-q", "--noise-threshold", "0.05"}) == 2);
    CHECK(read_image(refined.string()).meta("candela:sessions") == "1");
    REQUIRE(run({"render", "--resume", ckpt, "-q", "--noise-threshold", "0.02"}) == 0);
    ImageData a = read_image(direct.string()), b = read_image(refined.string());
    REQUIRE(a.channel_names == b.channel_names);
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
    CHECK(b.meta("candela:sessions") == "2");
    CHECK_FALSE(fs::exists(ckpt)); // kept only when asked again
    fs::remove_all(dir);
}

TEST_CASE("resuming after the scene file changed is refused", "[resume][slow]") {
    fs::path dir = fs::temp_directory_path() / ("candela-resume-s-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const fs::path scene = dir / "scene.dae", out = dir / "out.exr";
    fs::copy_file(kScene, scene);
    CHECK(render_and_interrupt(scene.string(), out, SIGINT) == 5);
    {
        std::ofstream f(scene, std::ios::app);
        f << "<!-- edited -->\n";
    }
    CHECK(run({"render", "--resume", out.string() + ".ckpt", "-q"}) == 2);
    fs::remove_all(dir);
}

TEST_CASE("unwritable output fails before rendering and leaves nothing", "[resume][quick]") {
    fs::path dir = fs::temp_directory_path() / ("candela-unwritable-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    CHECK(run({"render", kScene, "-q", "-f", (dir / "missing" / "x.exr").string()}) == 4);
    CHECK(run({"render", kScene, "-q", "-f", kScene}) != 0); // never overwrite the input
    CHECK(fs::is_empty(dir));
    fs::remove_all(dir);
}
