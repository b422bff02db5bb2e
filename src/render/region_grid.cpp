// The coarse grid of cells over an image that the stats block and `candela compare` report.
#include "candela/render/region_grid.h"

#include <algorithm>
#include <cmath>

namespace candela {

RegionGrid region_grid(int w, int h) {
    RegionGrid g;
    if (w <= 0 || h <= 0) return g;
    g.cols = std::min(kRegionColumns, w);
    g.rows = std::max(1, std::min(h, int(std::lround(double(g.cols) * h / w))));
    for (int r = 0; r < g.rows; ++r)
        for (int c = 0; c < g.cols; ++c)
            g.cells.push_back(
                {c * w / g.cols, r * h / g.rows, (c + 1) * w / g.cols, (r + 1) * h / g.rows});
    return g;
}

int RegionGrid::cell_of(int x, int y) const {
    // Cells are the integer partitions c*w/cols: search the row and column rather than invert
    // the division, whose rounding would need care at the boundaries.
    int r = 0, c = 0;
    while (r + 1 < rows && y >= at(r + 1, 0).y0)
        ++r;
    while (c + 1 < cols && x >= at(0, c + 1).x0)
        ++c;
    return r * cols + c;
}

} // namespace candela
