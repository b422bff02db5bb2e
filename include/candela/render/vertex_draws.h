#pragma once
// The sample draws of a camera sample by name. Every use of a random number has a fixed
// dimension, the same in every sample of a pixel, so that a (0,2)-sequence stratifies each use
// across the pixel's samples. A path vertex's draws are named (VertexDraw) and declared once, in
// dimension order, when the integrator is built (DimensionLayout::declare); their dimensions,
// the plan SampleBatch::fill computes for a step and the values the estimators read
// (VertexSamples) all follow from that declaration, so nothing else lists them in order.
// Whether a vertex's next-event estimate, BSDF sample or roulette test happens (a delta vertex
// skips next-event estimation, roulette starts late) never moves the dimensions of the others.
#include "candela/math/vec.h"
#include "candela/sampling/sample_batch.h"

#include <array>
#include <cstdint>
#include <initializer_list>
#include <vector>

namespace candela {

/// The draws of one path vertex, X(name, dimensions, bits), where `bits` marks a draw read as
/// raw 32-bit values (get_1d_bits, get_2d_bits) instead of floats:
/// - light_fill: the path integrator's bits spread below a light choice's place within the
///   chosen light's share (spread_within, light_choice.h); drawn only with more than one light;
/// - light_point: one 2-D point that chooses the light (its first coordinate, all 32 bits) and
///   places the light's sample (a mesh light's triangle, an environment map's texel: unit_cdf.h);
/// - hemisphere_direction: -H's uniform direction over the hemisphere (or the sphere);
/// - bsdf_direction: the BSDF sample's direction (with its cosine-weighted direction where a
///   Lambertian surface may use it);
/// - bsdf_lobe: the lobe choice, drawn only by materials that choose a lobe;
/// - roulette: the Russian roulette number (path integrator), drawn at this vertex or, when the
///   test was deferred past a specular or glossy lobe, at the next.
#define CANDELA_VERTEX_DRAWS(X)                                                                    \
    X(light_fill, 1, true)                                                                         \
    X(light_point, 2, true)                                                                        \
    X(hemisphere_direction, 2, false)                                                              \
    X(bsdf_direction, 2, false)                                                                    \
    X(bsdf_lobe, 1, false)                                                                         \
    X(roulette, 1, false)

enum class VertexDraw : std::uint8_t {
#define CANDELA_VERTEX_DRAW_NAME(name, dims, bits) name,
    CANDELA_VERTEX_DRAWS(CANDELA_VERTEX_DRAW_NAME)
#undef CANDELA_VERTEX_DRAW_NAME
};
constexpr std::size_t kVertexDrawCount = 0
#define CANDELA_VERTEX_DRAW_COUNT(name, dims, bits) +1
    CANDELA_VERTEX_DRAWS(CANDELA_VERTEX_DRAW_COUNT);
#undef CANDELA_VERTEX_DRAW_COUNT

/// The dimensions of one camera sample: the camera's two draws, then one run of `stride()`
/// dimensions per path vertex holding its declared draws.
class DimensionLayout {
  public:
    static constexpr std::uint32_t kFilm = 0;        ///< 2: position inside the pixel
    static constexpr std::uint32_t kLens = 2;        ///< 2: thin-lens aperture point
    static constexpr std::uint32_t kFirstVertex = 4; ///< first dimension of vertex 0

    /// A draw of a declaration: `planned` asks SampleBatch to compute it for every path of a
    /// step (a draw some configuration never makes keeps its dimensions, unplanned); `cosine`
    /// asks for a 2-D float point's cosine-weighted direction too (PlannedDraw::cosine).
    struct Member {
        VertexDraw draw;
        bool planned = true;
        bool cosine = false;
    };

    /// Declares the next draws of a vertex: `members` one after another, the whole group
    /// repeated `count` times (draw k of a member is in repetition k).
    void repeat(std::uint32_t count, std::initializer_list<Member> members);
    /// Declares one draw, made once per vertex.
    void add(Member member) { repeat(1, {member}); }

    /// Dimensions per vertex: the sum of everything declared.
    std::uint32_t stride() const { return stride_; }
    /// First dimension of path vertex `depth` (0 = the camera ray's hit).
    std::uint32_t vertex(int depth) const {
        return kFirstVertex + stride_ * static_cast<std::uint32_t>(depth);
    }
    /// Whether the declaration holds `draw` (at least once).
    bool declared(VertexDraw draw) const { return slots_[index(draw)].count > 0; }
    /// The first dimension of repetition k of `draw` at vertex `depth`.
    std::uint32_t dim(VertexDraw draw, int depth, std::uint32_t k = 0) const {
        return vertex(depth) + offset(draw, k);
    }
    /// The first dimension of repetition k of `draw` from its vertex's first dimension.
    std::uint32_t offset(VertexDraw draw, std::uint32_t k = 0) const {
        const Slot& s = slots_[index(draw)];
        return s.offset + k * s.group;
    }
    /// Appends the planned draws of vertex `depth` (roulette aside, whose use depends on the
    /// path: the integrator plans it) to `plan`, in dimension order.
    void plan(int depth, std::vector<PlannedDraw>& plan) const;

  private:
    struct Slot {
        std::uint32_t offset = 0; ///< first dimension of repetition 0, from the vertex's first
        std::uint32_t group = 0;  ///< dimensions of one repetition of its group
        std::uint32_t count = 0;  ///< repetitions (0: not declared)
        bool planned = false;
        bool cosine = false;
    };
    /// Draws of one repeat() call, order_[begin, end) repeated `count` times.
    struct Group {
        std::size_t begin, end;
        std::uint32_t count;
    };
    static std::size_t index(VertexDraw d) { return static_cast<std::size_t>(d); }
    static std::uint32_t dimensions(VertexDraw d) {
        static constexpr std::uint32_t kDimensions[] = {
#define CANDELA_VERTEX_DRAW_DIMS(name, dims, bits) dims,
            CANDELA_VERTEX_DRAWS(CANDELA_VERTEX_DRAW_DIMS)
#undef CANDELA_VERTEX_DRAW_DIMS
        };
        return kDimensions[index(d)];
    }
    static bool bits(VertexDraw d) {
        static constexpr bool kBits[] = {
#define CANDELA_VERTEX_DRAW_BITS(name, dims, bits) bits,
            CANDELA_VERTEX_DRAWS(CANDELA_VERTEX_DRAW_BITS)
#undef CANDELA_VERTEX_DRAW_BITS
        };
        return kBits[index(d)];
    }

    std::array<Slot, kVertexDrawCount> slots_{};
    std::vector<VertexDraw> order_; ///< the declared draws, in the order of their declaration
    std::vector<Group> groups_;
    std::uint32_t stride_ = 0;
};

inline void DimensionLayout::repeat(std::uint32_t count, std::initializer_list<Member> members) {
    std::uint32_t group = 0;
    for (const Member& m : members)
        group += dimensions(m.draw);
    const std::size_t begin = order_.size();
    std::uint32_t offset = stride_;
    for (const Member& m : members) {
        slots_[index(m.draw)] = {offset, group, count, m.planned, m.cosine};
        offset += dimensions(m.draw);
        order_.push_back(m.draw);
    }
    groups_.push_back({begin, order_.size(), count});
    stride_ += group * count;
}

inline void DimensionLayout::plan(int depth, std::vector<PlannedDraw>& plan) const {
    for (const Group& g : groups_)
        for (std::uint32_t k = 0; k < g.count; ++k)
            for (std::size_t j = g.begin; j < g.end; ++j) {
                const VertexDraw d = order_[j];
                const Slot& s = slots_[index(d)];
                if (s.planned)
                    plan.push_back({dim(d, depth, k), dimensions(d) == 2, s.cosine, bits(d)});
            }
}

/// The draws of one path vertex by name, served from the path's sampler (the batch values a step
/// planned, SampleBatch): each call reads the dimensions DimensionLayout gives the draw.
class VertexSamples {
  public:
    VertexSamples(PathSampler& sampler, const DimensionLayout& layout, int depth)
        : sampler_(sampler), layout_(layout), depth_(depth), first_(layout.vertex(depth)) {}

    [[gnu::always_inline]] float get_1d(VertexDraw d, std::uint32_t k = 0) {
        at(d, k);
        return sampler_.get_1d();
    }
    [[gnu::always_inline]] Vec2 get_2d(VertexDraw d, std::uint32_t k = 0) {
        at(d, k);
        return sampler_.get_2d();
    }
    [[gnu::always_inline]] std::uint32_t get_1d_bits(VertexDraw d, std::uint32_t k = 0) {
        at(d, k);
        return sampler_.get_1d_bits();
    }
    [[gnu::always_inline]] Bits2 get_2d_bits(VertexDraw d, std::uint32_t k = 0) {
        at(d, k);
        return sampler_.get_2d_bits();
    }
    /// get_2d(d), and its cosine-weighted direction in *cosine where the plan computed it
    /// (PathSampler::get_2d_cosine).
    [[gnu::always_inline]] bool get_2d_cosine(VertexDraw d, Vec2* u, Vec3* cosine) {
        at(d, 0);
        return sampler_.get_2d_cosine(u, cosine);
    }
    /// The same path's draws at its previous vertex (the roulette number it deferred).
    VertexSamples previous() const { return VertexSamples(sampler_, layout_, depth_ - 1); }

  private:
    void at(VertexDraw d, std::uint32_t k) {
        sampler_.set_dimension(first_ + layout_.offset(d, k));
    }

    PathSampler& sampler_;
    const DimensionLayout& layout_;
    int depth_;
    std::uint32_t first_; ///< the vertex's first dimension
};

} // namespace candela
