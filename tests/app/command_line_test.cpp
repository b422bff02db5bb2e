// The `candela` executable as a user meets it: help text, exit statuses, error messages and
// the promise that a failed run leaves no output file.
#include <catch2/catch.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

struct Run {
    int status = -1;
    std::string output; ///< stdout and stderr together
};

Run run(const std::string& args) {
    std::string cmd = std::string(CANDELA_BINARY) + " " + args + " 2>&1";
    Run r;
    FILE* p = ::popen(cmd.c_str(), "r");
    REQUIRE(p != nullptr);
    std::array<char, 4096> buf;
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0)
        r.output.append(buf.data(), n);
    int st = ::pclose(p);
    r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
    return r;
}

const std::string kScenes = CANDELA_PROJECT_SCENES;
const std::string kData = CANDELA_TEST_DATA;

} // namespace

TEST_CASE("help lists every subcommand and every render flag", "[app][quick]") {
    Run top = run("--help");
    CHECK(top.status == 0);
    for (const char* sub : {"render", "info", "check", "bench"})
        CHECK_THAT(top.output, Catch::Contains(sub));
    Run help = run("render --help");
    CHECK(help.status == 0);
    for (const char* flag : {"-s,--spp",
                             "-l,--light-samples",
                             "-t,--threads",
                             "-m,--max-depth",
                             "-o,--accumulate",
                             "-e,--env",
                             "-b,--lens-radius",
                             "-d,--focal-distance",
                             "-f,--output",
                             "-r,--resolution",
                             "-p,--region",
                             "-c,--camera-file",
                             "-a,--adaptive-sampling",
                             "-H,--hemisphere",
                             "--accel",
                             "--triangle",
                             "--seed",
                             "--sampler",
                             "--integrator",
                             "--no-mis",
                             "--aov",
                             "--camera",
                             "--strict",
                             "--resume",
                             "--checkpoint-every"})
        CHECK_THAT(help.output, Catch::Contains(flag));
}

TEST_CASE("exit statuses distinguish usage, scene and I/O errors", "[app][quick]") {
    fs::path dir = fs::temp_directory_path() / ("candela-app-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string out = (dir / "out.exr").string();

    Run bad_flag = run("render --spp 0 " + kScenes + "/cornell-box.dae -f " + out);
    CHECK(bad_flag.status == 2);
    CHECK_THAT(bad_flag.output, Catch::Contains("-s/--spp"));

    Run unknown = run("render --frobnicate " + kScenes + "/cornell-box.dae -f " + out);
    CHECK(unknown.status == 2);

    Run missing = run("render " + (dir / "nope.dae").string() + " -f " + out);
    CHECK(missing.status == 4);

    const std::string broken = kData + "/broken/01-malformed-xml.dae";
    Run bad_scene = run("render " + broken + " -q -f " + out);
    CHECK(bad_scene.status == 3);
    CHECK_THAT(bad_scene.output, Catch::StartsWith("candela: error: " + broken + ":"));
    CHECK_THAT(bad_scene.output, Catch::Contains(": error: "));

    // A frame whose film would not fit the memory limit fails before anything is allocated.
    Run too_big =
        run("render " + kScenes + "/cornell-box.dae -r 16000 16000 --max-memory 1G -f " + out);
    CHECK(too_big.status == 2);
    CHECK_THAT(too_big.output, Catch::Contains("--max-memory"));

    Run info_bad = run("info " + broken);
    CHECK(info_bad.status == 3);

    CHECK(fs::is_empty(dir)); // nothing half-written by any failed run

    Run info = run("info --json " + kScenes + "/cornell-spheres.dae");
    CHECK(info.status == 0);
    CHECK_THAT(info.output, Catch::Contains("\"spheres\""));

    Run ok = run("render " + kScenes + "/cornell-box.dae -r 16 12 -s 1 -q -f " + out);
    CHECK(ok.status == 0);
    CHECK(fs::exists(out));
    fs::remove_all(dir);
}
