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

TEST_CASE("the default memory limit is a real amount", "[limits][quick]") {
    CHECK(default_max_memory() > (std::uint64_t(64) << 20));
}
