// `candela check`: it compares at least two backends against the reference its --help names,
// counts its nouns, and explains its columns.
#include "app_support.h"

#include <catch2/catch.hpp>

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
