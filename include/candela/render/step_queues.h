#pragma once
// The queues one wavefront step fills while it shades its paths and empties when it traces them
// (rendering.md, "The render loop"): the shadow rays of next-event estimation, the probe rays of
// -H, and every continuing path's bounce ray. They are built as path_state.h builds the path
// state: a queue's per-entry fields are listed once (CANDELA_SHADOW_FIELDS,
// CANDELA_PROBE_FIELDS), its arrays and their growing are generated from that list, and the
// number of entries queued belongs to the queue, so a step passes the queue and nothing else.
#include "candela/accel/accel.h"
#include "candela/math/vec.h"
#include "candela/util/batch_kernel.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candela {

/// Rows of floats stored component-major for a vectorised batch kernel (integrator.cpp's
/// Columns): component k of row j is at in[k * stride + j]. The rows are gathered into `in`,
/// then the kernel computes all of them into `out` at once, laid out the same way.
struct ColumnTable {
    std::vector<float> in, out;
    std::size_t stride = 0; ///< batch_stride() of the most rows this step may hold
    std::size_t rows = 0;   ///< rows gathered in this step

    /// Grows both tables to hold `max_rows` rows of `in_components` and `out_components`
    /// components (never shrinks: a thread's workspace stops allocating).
    void reserve(std::size_t max_rows, int in_components, int out_components) {
        const std::size_t stride_max = batch_stride(max_rows);
        if (in.size() < stride_max * std::size_t(in_components))
            in.resize(stride_max * std::size_t(in_components));
        if (out.size() < stride_max * std::size_t(out_components))
            out.resize(stride_max * std::size_t(out_components));
    }
    /// Empties the table for a step that gathers at most `max_rows` rows.
    void start(std::size_t max_rows) {
        stride = batch_stride(max_rows);
        rows = 0;
    }
};

/// A shadow ray's fields, X(type, name):
/// - ray: the occlusion query; path: the path (index into PathArrays) it belongs to;
/// - value: what it adds to that path's L when unoccluded (already weighted);
/// - segment: its row of ShadowQueue::segments when it ends at a finite light's point (the ray
///   is computed there with the step's other segments), else -1 (the ray is written directly).
#define CANDELA_SHADOW_FIELDS(X)                                                                   \
    X(BatchRay, ray)                                                                               \
    X(std::uint32_t, path)                                                                         \
    X(Rgb, value)                                                                                  \
    X(std::int32_t, segment)

/// A probe ray's fields (-H's hemisphere rays looking for emitters), X(type, name):
/// - ray: the closest-hit query; path: the path it belongs to;
/// - weight: beta f |cos| / (pdf n) of its direction, times the radiance it finds.
#define CANDELA_PROBE_FIELDS(X)                                                                    \
    X(BatchRayHit, ray)                                                                            \
    X(std::uint32_t, path)                                                                         \
    X(Rgb, weight)

/// The members every queue of entries has, from its field list FIELDS: one array per field, the
/// count of entries queued in this step, growing the arrays, and adding an entry.
#define CANDELA_QUEUE_ARRAY(type, name) std::vector<type> name;
#define CANDELA_QUEUE_GROW(type, name)                                                             \
    if (name.size() < n) name.resize(n);
#define CANDELA_QUEUE_MEMBERS(FIELDS)                                                              \
    FIELDS(CANDELA_QUEUE_ARRAY)                                                                    \
    std::size_t size = 0; /* entries queued in this step */                                        \
    /** Grows every array to hold at least n entries (never shrinks). */                           \
    void reserve(std::size_t n){FIELDS(CANDELA_QUEUE_GROW)}                                        \
    /** The index of a new entry at the end; the caller writes every field of it. */               \
    std::size_t                                                                                    \
    add() {                                                                                        \
        return size++;                                                                             \
    }

/// The step's shadow rays, with the segments of those that end at a finite light's point: the
/// segment's two ends are gathered per ray (SegmentInput), then all of the step's segments are
/// computed in one vectorised loop before they are traced.
struct ShadowQueue {
    CANDELA_QUEUE_MEMBERS(CANDELA_SHADOW_FIELDS)
    ColumnTable segments;
    /// Empties the queue for a step that queues at most `max_entries` rays.
    void start(std::size_t max_entries) {
        size = 0;
        segments.start(max_entries);
    }
};

/// The step's probe rays (-H).
struct ProbeQueue {
    CANDELA_QUEUE_MEMBERS(CANDELA_PROBE_FIELDS)
    void start() { size = 0; }
};

#undef CANDELA_QUEUE_MEMBERS
#undef CANDELA_QUEUE_GROW
#undef CANDELA_QUEUE_ARRAY

/// The step's bounce rays, one row per live path (its index in PathArrays): a continuing path's
/// spawn point and direction (BounceInput), then the origins of all of them computed in one
/// vectorised loop (the rows of paths that end are computed too, from stale inputs, and never
/// read: a loop without gaps is what vectorises). Its count, `table.rows`, is the step's live
/// paths.
struct BounceQueue {
    ColumnTable table;
    void start(std::size_t live) {
        table.start(live);
        table.rows = live;
    }
};

} // namespace candela
