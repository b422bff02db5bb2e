#include "candela/render/memory_budget.h"
#include "candela/scene/scene.h"
#include "candela/util/error.h"

#include <catch2/catch.hpp>

using namespace candela;

TEST_CASE("memory estimate grows with the frame and the scene", "[limits][quick]") {
    Scene scene;
    RenderSettings s;
    s.width = 800;
    s.height = 600;
    MemoryEstimate small = estimate_render_memory(scene, s);
    CHECK(small.film > 800u * 600u * 24u);
    s.width = s.height = 32768;
    MemoryEstimate huge = estimate_render_memory(scene, s);
    CHECK(huge.film > (std::uint64_t(100) << 30)); // > 100 GiB for a 1 Gpixel film
    CHECK_THROWS_AS(check_memory_budget(huge, default_max_memory()), Error);
    CHECK_NOTHROW(check_memory_budget(small, default_max_memory()));
    s.region = Region{0, 0, 64, 64};
    CHECK(estimate_render_memory(scene, s).film < small.film); // a cell has a cell-sized film
}

TEST_CASE("memory sizes parse with units", "[limits][quick]") {
    CHECK(parse_memory_size("512M") == 512ull << 20);
    CHECK(parse_memory_size("8G") == 8ull << 30);
    CHECK(parse_memory_size("1.5GiB") == 3ull << 29);
    CHECK(parse_memory_size("1000") == 1000u);
    CHECK_THROWS_AS(parse_memory_size("lots"), Error);
    CHECK_THROWS_AS(parse_memory_size("8X"), Error);
    CHECK_THROWS_AS(parse_memory_size("0"), Error);
    CHECK(default_max_memory() > (std::uint64_t(64) << 20));
}
