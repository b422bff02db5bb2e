// The traversal kernel of the builtin BVH, compiled once per instruction set: bvh_sse2.cpp
// includes this file for SSE2 (the x86-64 baseline) and bvh_avx2.cpp includes it under an AVX2
// target pragma, each time inside an anonymous namespace, so that each translation unit has
// its own copy of the loop and of the leaf tests, built for its own instruction set. Only the
// box test of a node's eight children differs between the two: the includer defines that
// class, passed as `Box`, and includes every header this file uses beforehand.
//
// Box must provide: Box(const Ray&, const Vec3& inv_d); void set_tmax(float);
// unsigned test(const Bvh8Node&, float* tnear8) const, returning the bit mask of children whose
// box the ray enters within [tmin, tmax] and storing their entry distances.
//
// The leaf tests are functions of their own for reading's sake; they are forced inline, since
// the traversal loop runs them once per leaf it reaches.

/// pbrt-v4's conservative slab test: scaling the far distance by 1 + 2 gamma(n) covers the
/// n roundings of (bound - o) * inv_d, so no box is missed by a ray that hits its content.
/// The traversal folds the scale into the inverse direction used for far planes, which adds a
/// fourth rounding, hence gamma(4).
constexpr float kSlabFarScale = 1.f + 2.f * float_gamma(4);

/// Inner nodes on a path from the root that the traversal stack has room for: the builder's
/// bound bvh_detail::kBvhMaxDepth, rounded up.
constexpr int kTraceStackDepth = 100;
static_assert(kTraceStackDepth >= bvh_detail::kBvhMaxDepth,
              "the traversal stack must have room for the deepest path the builder makes");
/// Every inner node on the path to the current one leaves at most kBvhWidth - 1 of its
/// children on the stack; the current one pushes up to kBvhWidth before taking one off.
constexpr int kTraceStackSize = (kBvhWidth - 1) * kTraceStackDepth + kBvhWidth;

/// Float offset of the near (entry) plane of axis a in Bvh8Node::bounds for a ray whose inverse
/// direction component is `inv`; the far plane is at offset ^ kBvhWidth.
inline int near_plane_offset(int a, float inv) {
    return a * 2 * kBvhWidth + (inv < 0.f ? kBvhWidth : 0);
}

inline void prefetch_child(const BvhAccel::TraceData& data, std::uint32_t c) {
    if (c & kBvhLeafBit) {
        const char* p = reinterpret_cast<const char*>(data.leaves + bvh_detail::kLeafFloats *
                                                                        ((c & ~kBvhLeafBit) >> 3));
        _mm_prefetch(p, _MM_HINT_T0);
        _mm_prefetch(p + 64, _MM_HINT_T0);
        _mm_prefetch(p + 128, _MM_HINT_T0);
    } else {
        const char* p = reinterpret_cast<const char*>(data.nodes + c);
        _mm_prefetch(p, _MM_HINT_T0);
        _mm_prefetch(p + 64, _MM_HINT_T0);
        _mm_prefetch(p + 128, _MM_HINT_T0);
        _mm_prefetch(p + 192, _MM_HINT_T0);
    }
}

/// Which sphere tests a kernel carries (bvh_detail::KernelSet's middle index).
enum SphereMode : int {
    kNoSpheres = 0,   ///< triangles only: no sphere code at all
    kTrueSpheres = 1, ///< spheres, none of them an ellipsoid: the leaf's centre and radius suffice
    kEllipsoids = 2   ///< some spheres are ellipsoids: each sphere lane reads its Sphere record
};

/// A traversal stack entry: a child reference and the distance at which the ray enters its box.
struct StackEntry {
    std::uint32_t ref;
    float t;
};

/// What the leaf tests read of the ray, set up once per traversal.
struct LeafRay {
    const Ray& ray;
    __m128 ox, oy, oz; ///< the origin, broadcast
    __m128 dx, dy, dz; ///< the direction, broadcast
    __m128 vtmin;      ///< ray.tmin, broadcast
    WatertightRay wr;  ///< the shear of the watertight test (watertight kernels only)
};

/// The closest hit so far (its distance is the traversal's tmax): the leaf data of its
/// primitive's leaf (base, c primitives) and its lane there, with its barycentrics.
struct BestHit {
    const float* base = nullptr;
    std::uint32_t c = 0, lane = 0;
    float u = 0.f, v = 0.f;
};

/// Bit mask of the lanes of the leaf (base, c primitives) that hold spheres: their refs are at
/// least data.sphere_first_ref. Always 0 for kernels without sphere code.
template <bool kSpheres>
[[gnu::always_inline]] inline unsigned leaf_sphere_mask(const BvhAccel::TraceData& data,
                                                        const float* base, std::uint32_t c) {
    if (!kSpheres) return 0;
    const __m128i refs = _mm_loadu_si128(reinterpret_cast<const __m128i*>(base + 9 * c));
    const __m128i first = _mm_set1_epi32(static_cast<std::int32_t>(data.sphere_first_ref) - 1);
    return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(refs, first)))) &
           ((1u << c) - 1);
}

/// Moller-Trumbore tests of the triangles of the leaf (base, c primitives; lanes in sphere_mask
/// skipped), four in one SSE pass with exactly the operations (and their order) of
/// intersect_triangle_mt, so t, u and v are bit-identical to the scalar test (e1 and e2 were
/// computed by the same float subtractions at build time). True when a triangle is hit with t
/// in (tmin, tmax]; unless kAnyHit, tmax and best then hold the closest such hit.
template <bool kAnyHit>
[[gnu::always_inline]] inline bool leaf_triangles_mt(const LeafRay& r, const float* base,
                                                     std::uint32_t c, unsigned sphere_mask,
                                                     __m128 vtmax, float& tmax, BestHit& best) {
    const __m128 one = _mm_set1_ps(1.f), zero = _mm_setzero_ps();
    const __m128 p0x = _mm_loadu_ps(base), p0y = _mm_loadu_ps(base + c),
                 p0z = _mm_loadu_ps(base + 2 * c);
    const __m128 e1x = _mm_loadu_ps(base + 3 * c), e1y = _mm_loadu_ps(base + 4 * c),
                 e1z = _mm_loadu_ps(base + 5 * c);
    const __m128 e2x = _mm_loadu_ps(base + 6 * c), e2y = _mm_loadu_ps(base + 7 * c),
                 e2z = _mm_loadu_ps(base + 8 * c);
    // pvec = cross(d, e2)
    const __m128 px = _mm_sub_ps(_mm_mul_ps(r.dy, e2z), _mm_mul_ps(r.dz, e2y));
    const __m128 py = _mm_sub_ps(_mm_mul_ps(r.dz, e2x), _mm_mul_ps(r.dx, e2z));
    const __m128 pz = _mm_sub_ps(_mm_mul_ps(r.dx, e2y), _mm_mul_ps(r.dy, e2x));
    const __m128 det =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)), _mm_mul_ps(e1z, pz));
    const __m128 inv_det = _mm_div_ps(one, det);
    const __m128 tx = _mm_sub_ps(r.ox, p0x), ty = _mm_sub_ps(r.oy, p0y), tz = _mm_sub_ps(r.oz, p0z);
    const __m128 u = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(tx, px), _mm_mul_ps(ty, py)), _mm_mul_ps(tz, pz)),
        inv_det);
    // qvec = cross(tvec, e1)
    const __m128 qx = _mm_sub_ps(_mm_mul_ps(ty, e1z), _mm_mul_ps(tz, e1y));
    const __m128 qy = _mm_sub_ps(_mm_mul_ps(tz, e1x), _mm_mul_ps(tx, e1z));
    const __m128 qz = _mm_sub_ps(_mm_mul_ps(tx, e1y), _mm_mul_ps(ty, e1x));
    const __m128 v = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(r.dx, qx), _mm_mul_ps(r.dy, qy)), _mm_mul_ps(r.dz, qz)),
        inv_det);
    const __m128 t = _mm_mul_ps(
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)), _mm_mul_ps(e2z, qz)),
        inv_det);
    __m128 ok = _mm_cmpneq_ps(det, zero);
    ok = _mm_and_ps(ok, _mm_cmpge_ps(u, zero));
    ok = _mm_and_ps(ok, _mm_cmple_ps(u, one));
    ok = _mm_and_ps(ok, _mm_cmpge_ps(v, zero));
    ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_add_ps(u, v), one));
    ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, r.vtmin));
    ok = _mm_and_ps(ok, _mm_cmple_ps(t, vtmax));
    unsigned hits = static_cast<unsigned>(_mm_movemask_ps(ok)) & ((1u << c) - 1) & ~sphere_mask;
    if (!hits) return false;
    if (kAnyHit) return true;
    alignas(16) float ts[4], us[4], vs[4];
    _mm_store_ps(ts, t);
    _mm_store_ps(us, u);
    _mm_store_ps(vs, v);
    // In lane order with t <= tmax, as the scalar loop would accept them.
    while (hits) {
        const unsigned k = static_cast<unsigned>(__builtin_ctz(hits));
        hits &= hits - 1;
        if (ts[k] <= tmax) {
            tmax = ts[k];
            best = BestHit{base, c, k, us[k], vs[k]};
        }
    }
    return true;
}

/// Watertight tests of the triangles of the leaf (base, c primitives; lanes in sphere_mask
/// skipped), one lane at a time with the scalar test. True when a triangle is hit with t in
/// (tmin, tmax]; unless kAnyHit, tmax and best then hold the closest such hit.
template <bool kAnyHit>
[[gnu::always_inline]] inline bool leaf_triangles_watertight(const LeafRay& r, const float* base,
                                                             std::uint32_t c, unsigned sphere_mask,
                                                             float& tmax, BestHit& best) {
    bool found = false;
    for (std::uint32_t k = 0; k < c; ++k) {
        if ((sphere_mask >> k) & 1u) continue;
        const Vec3 p0(base[k], base[c + k], base[2 * c + k]);
        const Vec3 p1(base[3 * c + k], base[4 * c + k], base[5 * c + k]);
        const Vec3 p2(base[6 * c + k], base[7 * c + k], base[8 * c + k]);
        TriangleHit th;
        if (!intersect_triangle_watertight(r.ray.o, r.wr, p0, p1, p2, r.ray.tmin, tmax, th))
            continue;
        if (kAnyHit) return true;
        found = true;
        tmax = th.t;
        best = BestHit{base, c, k, th.u, th.v};
    }
    return found;
}

/// Tests of the spheres of the leaf (base, c primitives), the lanes in sphere_mask: from the
/// leaf's centre and radius, or for kEllipsoids from each sphere's record in data.spheres.
/// True when a sphere is hit with t in (tmin, tmax]; unless kAnyHit, tmax and best then hold
/// the closest such hit.
template <int kSphereMode, bool kAnyHit>
[[gnu::always_inline]] inline bool leaf_spheres(const BvhAccel::TraceData& data, const LeafRay& r,
                                                const float* base, std::uint32_t c,
                                                unsigned sphere_mask, float& tmax, BestHit& best) {
    bool found = false;
    for (std::uint32_t k = 0; k < c; ++k) {
        if (!((sphere_mask >> k) & 1u)) continue;
        float t;
        if (kSphereMode == kEllipsoids) {
            std::uint32_t sref;
            std::memcpy(&sref, base + 9 * c + k, sizeof sref);
            if (!intersect_sphere_prim(data.spheres[sref - data.sphere_first_ref], r.ray.o, r.ray.d,
                                       r.ray.tmin, tmax, t))
                continue;
        } else {
            const Vec3 center(base[k], base[c + k], base[2 * c + k]);
            if (!intersect_sphere(r.ray.o, r.ray.d, center, base[3 * c + k], r.ray.tmin, tmax, t))
                continue;
        }
        if (kAnyHit) return true;
        found = true;
        tmax = t;
        best = BestHit{base, c, k, 0.f, 0.f};
    }
    return found;
}

/// Orders the entries stack[first, sp) pushed for one node so that the next one to visit is on
/// top: closest hit visits the nearest first, occlusion the farthest first. Insertion sort,
/// stable, for at most kBvhWidth entries.
template <bool kAnyHit>
[[gnu::always_inline]] inline void order_pushed(StackEntry* stack, int first, int sp) {
    for (int i = first + 1; i < sp; ++i) {
        const StackEntry e = stack[i];
        int j = i;
        while (j > first && (kAnyHit ? stack[j - 1].t > e.t : stack[j - 1].t < e.t)) {
            stack[j] = stack[j - 1];
            --j;
        }
        stack[j] = e;
    }
}

template <class Box, TriangleTest kTest, int kSphereMode, bool kAnyHit>
bool trace(const BvhAccel::TraceData& data, const Ray& ray, BvhAccel::TraceHit& out) {
    constexpr bool kSpheres = kSphereMode != kNoSpheres;
    const Vec3 inv(1.f / ray.d.x, 1.f / ray.d.y, 1.f / ray.d.z);
    Box box(ray, inv);
    LeafRay lr{ray,
               _mm_set1_ps(ray.o.x),
               _mm_set1_ps(ray.o.y),
               _mm_set1_ps(ray.o.z),
               _mm_set1_ps(ray.d.x),
               _mm_set1_ps(ray.d.y),
               _mm_set1_ps(ray.d.z),
               _mm_set1_ps(ray.tmin),
               WatertightRay{}};
    if (kTest == TriangleTest::Watertight) lr.wr = make_watertight_ray(ray.d);
    float tmax = ray.tmax;
    __m128 vtmax = _mm_set1_ps(tmax);
    BestHit best;
    // After a leaf test found a closer hit: boxes beyond it need not be entered.
    auto narrow = [&] {
        vtmax = _mm_set1_ps(tmax);
        box.set_tmax(tmax);
    };

    // Stack of (child reference, box entry distance); entries beyond the closest hit found
    // meanwhile are dropped when popped.
    StackEntry stack[kTraceStackSize];
    int sp = 0;
    std::uint32_t ref = data.root;
    for (;;) {
        if (!(ref & kBvhLeafBit)) {
            const Bvh8Node& node = data.nodes[ref];
            // The child references sit on the node's fourth cache line, which the box test
            // does not touch: fetch it now so that its latency overlaps the box test's.
            _mm_prefetch(reinterpret_cast<const char*>(node.child), _MM_HINT_T0);
            alignas(32) float tn[kBvhWidth];
            unsigned mask = box.test(node, tn);
            if (mask != 0) {
                const std::uint32_t* child = node.child;
                const unsigned k0 = static_cast<unsigned>(__builtin_ctz(mask));
                mask &= mask - 1;
                if (mask == 0) {
                    ref = child[k0];
                    continue;
                }
                const unsigned k1 = static_cast<unsigned>(__builtin_ctz(mask));
                mask &= mask - 1;
                if (mask == 0) {
                    // Two children: continue with the nearer (closest hit) or the farther
                    // (occlusion) and push the other.
                    if ((tn[k0] <= tn[k1]) != kAnyHit) {
                        prefetch_child(data, child[k1]);
                        stack[sp++] = StackEntry{child[k1], tn[k1]};
                        ref = child[k0];
                    } else {
                        prefetch_child(data, child[k0]);
                        stack[sp++] = StackEntry{child[k0], tn[k0]};
                        ref = child[k1];
                    }
                    continue;
                }
                // Three to eight children: push them all, sort the pushed entries so that the
                // next one to visit is on top, and continue with it. Closest hit visits the
                // nearest first. Occlusion visits the farthest first: a shadow ray starts on a
                // surface whose surroundings rarely occlude it (measured in docs/traversal.md).
                const int first = sp;
                prefetch_child(data, child[k0]);
                prefetch_child(data, child[k1]);
                stack[sp++] = StackEntry{child[k0], tn[k0]};
                stack[sp++] = StackEntry{child[k1], tn[k1]};
                while (mask) {
                    const unsigned k = static_cast<unsigned>(__builtin_ctz(mask));
                    mask &= mask - 1;
                    prefetch_child(data, child[k]);
                    stack[sp++] = StackEntry{child[k], tn[k]};
                }
                order_pushed<kAnyHit>(stack, first, sp);
                ref = stack[--sp].ref;
                continue;
            }
        } else {
            const std::uint32_t c = (ref & 7u) + 1;
            const float* base = data.leaves + bvh_detail::kLeafFloats * ((ref & ~kBvhLeafBit) >> 3);
            const unsigned sphere_mask = leaf_sphere_mask<kSpheres>(data, base, c);
            const bool tri_hit =
                kTest == TriangleTest::MollerTrumbore
                    ? leaf_triangles_mt<kAnyHit>(lr, base, c, sphere_mask, vtmax, tmax, best)
                    : leaf_triangles_watertight<kAnyHit>(lr, base, c, sphere_mask, tmax, best);
            if (tri_hit) {
                if (kAnyHit) return true;
                narrow();
            }
            if (kSpheres && sphere_mask &&
                leaf_spheres<kSphereMode, kAnyHit>(data, lr, base, c, sphere_mask, tmax, best)) {
                if (kAnyHit) return true;
                narrow();
            }
        }
        // Pop the next node that still begins before the closest hit so far.
        while (sp > 0 && stack[sp - 1].t > tmax)
            --sp;
        if (sp == 0) break;
        ref = stack[--sp].ref;
    }
    if (!best.base) return false;
    std::uint32_t best_ref;
    std::memcpy(&best_ref, best.base + 9 * best.c + best.lane, sizeof best_ref);
    out = BvhAccel::TraceHit{tmax, best.u, best.v, best_ref};
    return true;
}

template <class Box> bvh_detail::KernelSet make_kernel_set() {
    constexpr TriangleTest MT = TriangleTest::MollerTrumbore, WT = TriangleTest::Watertight;
    bvh_detail::KernelSet s{};
    s.fn[0][0][0] = &trace<Box, MT, kNoSpheres, false>;
    s.fn[0][0][1] = &trace<Box, MT, kNoSpheres, true>;
    s.fn[0][1][0] = &trace<Box, MT, kTrueSpheres, false>;
    s.fn[0][1][1] = &trace<Box, MT, kTrueSpheres, true>;
    s.fn[0][2][0] = &trace<Box, MT, kEllipsoids, false>;
    s.fn[0][2][1] = &trace<Box, MT, kEllipsoids, true>;
    s.fn[1][0][0] = &trace<Box, WT, kNoSpheres, false>;
    s.fn[1][0][1] = &trace<Box, WT, kNoSpheres, true>;
    s.fn[1][1][0] = &trace<Box, WT, kTrueSpheres, false>;
    s.fn[1][1][1] = &trace<Box, WT, kTrueSpheres, true>;
    s.fn[1][2][0] = &trace<Box, WT, kEllipsoids, false>;
    s.fn[1][2][1] = &trace<Box, WT, kEllipsoids, true>;
    return s;
}
