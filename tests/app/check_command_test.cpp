// `candela check`: it compares at least two backends against the reference its --help names,
// counts its nouns, and explains its columns.
#include "app_support.h"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <regex>

using namespace candela::test;

TEST_CASE("check: at least two backends, counted nouns, a legend", "[app][check]") {
    check_one_line(run_candela({"check", "--procedural", "spheres:1", "--accel", "builtin"}), 2,
                   "give at least two");
    const Result r =
        run_candela({"check", "--procedural", "spheres:1", "--camera-rays", "8", "--bounce-rays",
                     "50", "--shadow-rays", "50", "--edge-rays", "50", "-t", "1"});
    INFO(r.out << r.err);
    CHECK(r.status == 0);
    CHECK_THAT(r.out, Catch::Contains("1 sphere;"));
    CHECK_THAT(r.out, Catch::Contains("brute vs "));
    for (const char* column : {"agree:", "tie:", "graze:", "precision:", "leak:"})
        CHECK_THAT(r.out, Catch::Contains(column));
    // --help names the reference the report uses (in text wrapped to the width: lines joined).
    const std::string help =
        std::regex_replace(run_candela({"check", "--help"}).out, std::regex("\n +"), " ");
    CHECK_THAT(help, Catch::Contains("brute when listed"));
}

TEST_CASE("check prints a handful of worst cases unless asked for more", "[app][check]") {
    // Rays aimed at the shared edges and vertices of a tessellated sphere: embree and builtin
    // disagree on many (grazes), far more than a screen of them.
    const std::vector<std::string> args = {"check",
                                           "--procedural",
                                           "sphere:2000",
                                           "--accel",
                                           "embree,builtin",
                                           "--camera-rays",
                                           "8",
                                           "--bounce-rays",
                                           "100",
                                           "--shadow-rays",
                                           "100",
                                           "--edge-rays",
                                           "4000",
                                           "-t",
                                           "1",
                                           "--json"};
    auto worst = [&](const std::vector<std::string>& extra) {
        const Result r = run_candela(cat(args, extra));
        INFO(r.err);
        REQUIRE(r.status == 0);
        return nlohmann::json::parse(r.out).at("worst").size();
    };
    REQUIRE(worst({"--worst-cases", "50"}) > 5); // the scene has more than the default shows
    CHECK(worst({}) == 5);
    CHECK(worst({"--worst-cases", "8"}) == 8);
}
