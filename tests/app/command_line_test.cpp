// The `candela` executable as a user meets it: help text, exit statuses, error messages and
// the promise that a failed run leaves no output file.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Run {
    int status = -1;
    std::string output; ///< stdout and stderr together
};

/// Runs candela with `args`; `env` (e.g. "NAME=value") is set for that run only.
Run run(const std::string& args, const std::string& env = "") {
    std::string cmd = env + (env.empty() ? "" : " ") + CANDELA_BINARY + " " + args + " 2>&1";
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
    const nlohmann::json info_json = nlohmann::json::parse(info.output, nullptr, false);
    REQUIRE_FALSE(info_json.is_discarded());
    CHECK(info_json.at("spheres") == 2);

    Run ok = run("render " + kScenes + "/cornell-box.dae -r 16 12 -s 1 -q -f " + out);
    CHECK(ok.status == 0);
    CHECK(fs::exists(out));
    fs::remove_all(dir);
}

// Start-up: OpenImageIO's dependency tree takes about half a second to load, so image I/O is a
// module (libcandela_image.so) loaded on the first image read or write. The dynamic loader's own
// report (LD_DEBUG=libs) shows what each command maps.
TEST_CASE("start-up: version and info map no OpenImageIO and version names what it was built with",
          "[app][quick]") {
    const Run version = run("--version", "LD_DEBUG=libs");
    REQUIRE(version.status == 0);
    CHECK_THAT(version.output, Catch::Contains("calling init: ")); // the loader did report
    CHECK_THAT(version.output, !Catch::Contains("libOpenImageIO"));
    CHECK_THAT(version.output, !Catch::Contains("/libcandela_image.so"));
    for (const char* line :
         {"candela ", "commit ", "build ", "embree ", "openimageio ", "builtin bvh kernel "})
        CHECK_THAT(version.output, Catch::Contains(line));

    const Run info = run("info " + kScenes + "/cornell-box.dae", "LD_DEBUG=libs");
    REQUIRE(info.status == 0);
    CHECK_THAT(info.output, Catch::Contains("calling init: "));
    CHECK_THAT(info.output, !Catch::Contains("libOpenImageIO"));

    // A render does load it (the output check writes a pixel through it before any work).
    fs::path out = fs::temp_directory_path() / ("candela-module-" + std::to_string(::getpid()));
    fs::create_directories(out);
    const Run render =
        run("render " + kScenes + "/cornell-box.dae -r 8 6 -s 1 -q -f " + (out / "a.exr").string(),
            "LD_DEBUG=libs");
    CHECK(render.status == 0);
    CHECK_THAT(render.output, Catch::Contains("libOpenImageIO"));
    fs::remove_all(out);
}

TEST_CASE("a missing image module is one error before any work, and nothing is written",
          "[app][quick]") {
    fs::path out = fs::temp_directory_path() / ("candela-nomodule-" + std::to_string(::getpid()));
    fs::create_directories(out);
    const std::string image = (out / "a.exr").string();
    const Run r = run("render " + kScenes + "/cornell-box.dae -r 8 6 -s 1 -f " + image,
                      "CANDELA_IMAGE_MODULE=" + (out / "missing.so").string());
    CHECK(r.status == 4);
    CHECK_THAT(r.output, Catch::StartsWith("candela: error: cannot load the image module"));
    CHECK_THAT(r.output, Catch::Contains("missing.so"));
    CHECK_THAT(r.output, !Catch::Contains("rendering")); // refused before the render
    CHECK(fs::is_empty(out));
    // Commands that need no image do not notice.
    CHECK(run("info " + kScenes + "/cornell-box.dae",
              "CANDELA_IMAGE_MODULE=" + (out / "missing.so").string())
              .status == 0);
    fs::remove_all(out);
}

TEST_CASE("an image module that cannot load stops the render with its error, writing nothing",
          "[app][quick]") {
    // The file is there, so the render starts; the module loads beside the render (after its
    // first pass) and fails there: the render stops, the error is the load's, no file is left.
    fs::path out = fs::temp_directory_path() / ("candela-badmodule-" + std::to_string(::getpid()));
    fs::create_directories(out);
    const fs::path module = out / "bad.so";
    std::FILE* f = std::fopen(module.string().c_str(), "w");
    REQUIRE(f != nullptr);
    std::fputs("not a shared library\n", f);
    std::fclose(f);
    const Run r = run("render " + kScenes + "/cornell-box.dae -r 8 6 -s 4 -a 1 0.001 -f " +
                          (out / "a.exr").string(),
                      "CANDELA_IMAGE_MODULE=" + module.string());
    CHECK(r.status == 4);
    CHECK_THAT(r.output, Catch::Contains("candela: error: cannot load the image module"));
    CHECK_THAT(r.output, Catch::Contains("bad.so"));
    std::vector<std::string> left;
    for (const auto& entry : fs::directory_iterator(out))
        left.push_back(entry.path().filename().string());
    CHECK(left == std::vector<std::string>{"bad.so"});
    fs::remove_all(out);
}
