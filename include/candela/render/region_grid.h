#pragma once
// The coarse grid over an image that the render stats block ("by region") and `candela compare`
// report per cell: kRegionColumns cells across (fewer for narrower images) and rows to match the
// aspect ratio, so one cell is about square. Cell (r, c) covers the pixels [x0, x1) x [y0, y1)
// with row 0 at the top of the image.
#include <vector>

namespace candela {

/// Cells across the grid (fewer when the image is narrower than this many pixels).
constexpr int kRegionColumns = 6;

struct GridCell {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    int pixel_count() const { return (x1 - x0) * (y1 - y0); }
};

struct RegionGrid {
    int rows = 0, cols = 0;
    std::vector<GridCell> cells; ///< rows * cols, row-major, top row first
    const GridCell& at(int r, int c) const {
        return cells[std::size_t(r) * std::size_t(cols) + std::size_t(c)];
    }
    /// The index into `cells` of the cell holding pixel (x, y).
    int cell_of(int x, int y) const;
};

/// The grid of a width x height image (empty for an empty image).
RegionGrid region_grid(int width, int height);

} // namespace candela
