#include "candela/util/check.h"

#include <catch2/catch.hpp>

#include <string>

using namespace candela;

TEST_CASE("CANDELA_CHECK throws an internal error naming the place and the condition",
          "[check][quick]") {
    int built = 0;
    auto message = [&] {
        ++built;
        return std::string("index 7 out of range");
    };
    CANDELA_CHECK(1 + 1 == 2, message());
    CHECK(built == 0); // the message is built only on failure
    try {
        CANDELA_CHECK(7 < 3, message());
        FAIL("CANDELA_CHECK did not throw");
    } catch (const Error& e) {
        CHECK(e.kind() == ErrorKind::Internal);
        const std::string what = e.what();
        CHECK(what.find("check_test.cpp:") != std::string::npos);
        CHECK(what.find("index 7 out of range") != std::string::npos);
        CHECK(what.find("(7 < 3)") != std::string::npos);
        CHECK(what.find('/') == std::string::npos); // no build paths
    }
    CHECK(built == 1);
}

TEST_CASE("CANDELA_DCHECK runs in debug builds only", "[check][quick]") {
    int evaluated = 0;
    auto fails = [&] {
        ++evaluated;
        return false;
    };
#ifdef NDEBUG
    CANDELA_DCHECK(fails(), "compiled out");
    CHECK(evaluated == 0);
#else
    CHECK_THROWS_AS([&] { CANDELA_DCHECK(fails(), "checked"); }(), Error);
    CHECK(evaluated == 1);
#endif
}
