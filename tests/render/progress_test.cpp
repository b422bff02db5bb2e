// The progress line's pieces: durations for people and a bar that fits its terminal.
#include "candela/render/progress.h"

#include <catch2/catch.hpp>

#include <algorithm>

using namespace candela;

TEST_CASE("durations: tenths of a second, then m:ss, then h:mm:ss", "[progress][quick]") {
    CHECK(format_duration(0.0) == "0.0s");
    CHECK(format_duration(42.34) == "42.3s");
    CHECK(format_duration(59.9) == "59.9s");
    CHECK(format_duration(59.97) == "1:00");
    CHECK(format_duration(252.0) == "4:12");
    CHECK(format_duration(3599.4) == "59:59");
    CHECK(format_duration(3723.0) == "1:02:03");
    CHECK(format_duration(-1.0) == "0.0s");
}

TEST_CASE("the progress bar fills the terminal's width and no more", "[progress][quick]") {
    for (int columns : {50, 60, 79, 80, 132, 200}) {
        INFO(columns);
        const std::string line = progress_bar_line(0.5, 252.0, 61.0, columns);
        CHECK(int(line.size()) == columns - 1);
        CHECK(line.front() == '[');
        CHECK(line.find("] ") != std::string::npos);
        CHECK(line.find(" 50.0%  4:12 elapsed  ETA 1:01") != std::string::npos);
        // Half the bar is filled.
        const std::size_t bar = line.find(']') - 1;
        const std::size_t filled = std::size_t(std::count(line.begin(), line.end(), '='));
        CHECK(filled == bar / 2);
    }
    CHECK(progress_bar_line(1.0, 1.0, 0.0, 60).find("[=") == 0);
    const std::string full = progress_bar_line(1.0, 1.0, 0.0, 60);
    CHECK(full.find(' ') == full.find(']') + 1); // no gap in a full bar
    // Too narrow for a bar: the numbers alone, cut to fit.
    CHECK(progress_bar_line(0.5, 1.0, 1.0, 30).front() != '[');
    CHECK(progress_bar_line(0.5, 1.0, 1.0, 30).size() <= 29);
    CHECK(progress_bar_line(0.5, 1.0, 1.0, 12).size() == 11);
}

TEST_CASE("the progress fraction never goes back when the estimated total grows",
          "[progress][quick]") {
    CHECK(progress_fraction(50, 100, 1.0, 0.0, 0.0) == 0.5);
    // An adaptive render's total estimate doubles: 60 / 200 = 0.3, but 0.5 was shown before.
    CHECK(progress_fraction(60, 200, 2.0, 0.0, 0.5) == 0.5);
    CHECK(progress_fraction(150, 200, 3.0, 0.0, 0.5) == 0.75);
    // A time budget moves the fraction on as it runs out; more samples than estimated is all.
    CHECK(progress_fraction(10, 100, 5.0, 10.0, 0.0) == 0.5);
    CHECK(progress_fraction(120, 100, 1.0, 0.0, 0.0) == 1.0);
}
