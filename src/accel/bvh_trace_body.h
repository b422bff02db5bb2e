// The traversal loop of the builtin BVH, included by bvh.cpp (SSE2) and bvh_avx2.cpp (under an
// AVX2 target pragma), each time inside an anonymous namespace so that every translation unit
// compiles its own copy for its own instruction set. The includer defines the box tester
// class passed as `Box` and includes every header this file uses beforehand.
//
// Box must provide: Box(const Ray&, const Vec3& inv_d); void set_tmax(float);
// unsigned test(const Bvh8Node&, float* tnear8) const, returning the bit mask of children whose
// box the ray enters within [tmin, tmax] and storing their entry distances.

/// pbrt-v4's conservative slab test: scaling the far distance by 1 + 2 gamma(n) covers the
/// n roundings of (bound - o) * inv_d, so no box is missed by a ray that hits its content.
/// The traversal folds the scale into the inverse direction used for far planes, which adds a
/// fourth rounding, hence gamma(4).
constexpr float kSlabFarScale = 1.f + 2.f * float_gamma(4);
/// A BVH8 path from the root has at most this many inner nodes (one binary split level at
/// least per node; the build caps binary split depth at 96), each pushing at most 7 children.
constexpr int kTraceStackSize = 7 * 100 + 8;

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

template <class Box, TriangleTest kTest, int kSphereMode, bool kAnyHit>
bool trace(const BvhAccel::TraceData& data, const Ray& ray, BvhAccel::TraceHit& out) {
    constexpr bool kSpheres = kSphereMode != kNoSpheres;
    const Vec3 inv(1.f / ray.d.x, 1.f / ray.d.y, 1.f / ray.d.z);
    Box box(ray, inv);
    const __m128 ox = _mm_set1_ps(ray.o.x), oy = _mm_set1_ps(ray.o.y), oz = _mm_set1_ps(ray.o.z);
    const __m128 dx = _mm_set1_ps(ray.d.x), dy = _mm_set1_ps(ray.d.y), dz = _mm_set1_ps(ray.d.z);
    WatertightRay wr;
    if (kTest == TriangleTest::Watertight) wr = make_watertight_ray(ray.d);
    const float tmin = ray.tmin;
    float tmax = ray.tmax;
    const __m128 vtmin = _mm_set1_ps(tmin);
    __m128 vtmax = _mm_set1_ps(tmax);
    const __m128 one = _mm_set1_ps(1.f), zero = _mm_setzero_ps();

    const float* best_base = nullptr;
    std::uint32_t best_c = 0, best_lane = 0;
    float best_u = 0.f, best_v = 0.f;

    // Stack of (child reference, box entry distance); entries beyond the closest hit found
    // meanwhile are dropped when popped.
    struct Entry {
        std::uint32_t ref;
        float t;
    };
    Entry stack[kTraceStackSize];
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
                        stack[sp++] = Entry{child[k1], tn[k1]};
                        ref = child[k0];
                    } else {
                        prefetch_child(data, child[k0]);
                        stack[sp++] = Entry{child[k0], tn[k0]};
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
                stack[sp++] = Entry{child[k0], tn[k0]};
                stack[sp++] = Entry{child[k1], tn[k1]};
                while (mask) {
                    const unsigned k = static_cast<unsigned>(__builtin_ctz(mask));
                    mask &= mask - 1;
                    prefetch_child(data, child[k]);
                    stack[sp++] = Entry{child[k], tn[k]};
                }
                for (int i = first + 1; i < sp; ++i) {
                    const Entry e = stack[i];
                    int j = i;
                    while (j > first && (kAnyHit ? stack[j - 1].t > e.t : stack[j - 1].t < e.t)) {
                        stack[j] = stack[j - 1];
                        --j;
                    }
                    stack[j] = e;
                }
                ref = stack[--sp].ref;
                continue;
            }
        } else {
            const std::uint32_t c = (ref & 7u) + 1;
            const float* base = data.leaves + bvh_detail::kLeafFloats * ((ref & ~kBvhLeafBit) >> 3);
            unsigned sphere_mask = 0;
            if (kSpheres) {
                const __m128i refs =
                    _mm_loadu_si128(reinterpret_cast<const __m128i*>(base + 9 * c));
                const __m128i first =
                    _mm_set1_epi32(static_cast<std::int32_t>(data.sphere_first_ref) - 1);
                sphere_mask = static_cast<unsigned>(
                                  _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(refs, first)))) &
                              ((1u << c) - 1);
            }
            if (kTest == TriangleTest::MollerTrumbore) {
                // Four Moller-Trumbore tests with exactly the operations (and their order) of
                // intersect_triangle_mt, so t, u and v are bit-identical to the scalar test
                // (e1 and e2 were computed by the same float subtractions at build time).
                const __m128 p0x = _mm_loadu_ps(base), p0y = _mm_loadu_ps(base + c),
                             p0z = _mm_loadu_ps(base + 2 * c);
                const __m128 e1x = _mm_loadu_ps(base + 3 * c), e1y = _mm_loadu_ps(base + 4 * c),
                             e1z = _mm_loadu_ps(base + 5 * c);
                const __m128 e2x = _mm_loadu_ps(base + 6 * c), e2y = _mm_loadu_ps(base + 7 * c),
                             e2z = _mm_loadu_ps(base + 8 * c);
                // pvec = cross(d, e2)
                const __m128 px = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(dz, e2y));
                const __m128 py = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(dx, e2z));
                const __m128 pz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(dy, e2x));
                const __m128 det = _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, px), _mm_mul_ps(e1y, py)),
                                              _mm_mul_ps(e1z, pz));
                const __m128 inv_det = _mm_div_ps(one, det);
                const __m128 tx = _mm_sub_ps(ox, p0x), ty = _mm_sub_ps(oy, p0y),
                             tz = _mm_sub_ps(oz, p0z);
                const __m128 u =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(tx, px), _mm_mul_ps(ty, py)),
                                          _mm_mul_ps(tz, pz)),
                               inv_det);
                // qvec = cross(tvec, e1)
                const __m128 qx = _mm_sub_ps(_mm_mul_ps(ty, e1z), _mm_mul_ps(tz, e1y));
                const __m128 qy = _mm_sub_ps(_mm_mul_ps(tz, e1x), _mm_mul_ps(tx, e1z));
                const __m128 qz = _mm_sub_ps(_mm_mul_ps(tx, e1y), _mm_mul_ps(ty, e1x));
                const __m128 v =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)),
                                          _mm_mul_ps(dz, qz)),
                               inv_det);
                const __m128 t =
                    _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)),
                                          _mm_mul_ps(e2z, qz)),
                               inv_det);
                __m128 ok = _mm_cmpneq_ps(det, zero);
                ok = _mm_and_ps(ok, _mm_cmpge_ps(u, zero));
                ok = _mm_and_ps(ok, _mm_cmple_ps(u, one));
                ok = _mm_and_ps(ok, _mm_cmpge_ps(v, zero));
                ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_add_ps(u, v), one));
                ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, vtmin));
                ok = _mm_and_ps(ok, _mm_cmple_ps(t, vtmax));
                unsigned hits =
                    static_cast<unsigned>(_mm_movemask_ps(ok)) & ((1u << c) - 1) & ~sphere_mask;
                if (hits) {
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
                            best_base = base;
                            best_c = c;
                            best_lane = k;
                            best_u = us[k];
                            best_v = vs[k];
                        }
                    }
                    vtmax = _mm_set1_ps(tmax);
                    box.set_tmax(tmax);
                }
            } else {
                bool found = false;
                for (std::uint32_t k = 0; k < c; ++k) {
                    if (kSpheres && (sphere_mask >> k) & 1u) continue;
                    const Vec3 p0(base[k], base[c + k], base[2 * c + k]);
                    const Vec3 p1(base[3 * c + k], base[4 * c + k], base[5 * c + k]);
                    const Vec3 p2(base[6 * c + k], base[7 * c + k], base[8 * c + k]);
                    TriangleHit th;
                    if (!intersect_triangle_watertight(ray.o, wr, p0, p1, p2, tmin, tmax, th))
                        continue;
                    if (kAnyHit) return true;
                    found = true;
                    tmax = th.t;
                    best_base = base;
                    best_c = c;
                    best_lane = k;
                    best_u = th.u;
                    best_v = th.v;
                }
                if (found) {
                    vtmax = _mm_set1_ps(tmax);
                    box.set_tmax(tmax);
                }
            }
            if (kSpheres && sphere_mask) {
                bool found = false;
                for (std::uint32_t k = 0; k < c; ++k) {
                    if (!((sphere_mask >> k) & 1u)) continue;
                    float t;
                    if (kSphereMode == kEllipsoids) {
                        std::uint32_t sref;
                        std::memcpy(&sref, base + 9 * c + k, sizeof sref);
                        if (!intersect_sphere_prim(data.spheres[sref - data.sphere_first_ref],
                                                   ray.o, ray.d, tmin, tmax, t))
                            continue;
                    } else {
                        const Vec3 center(base[k], base[c + k], base[2 * c + k]);
                        if (!intersect_sphere(ray.o, ray.d, center, base[3 * c + k], tmin, tmax, t))
                            continue;
                    }
                    if (kAnyHit) return true;
                    found = true;
                    tmax = t;
                    best_base = base;
                    best_c = c;
                    best_lane = k;
                    best_u = best_v = 0.f;
                }
                if (found) {
                    vtmax = _mm_set1_ps(tmax);
                    box.set_tmax(tmax);
                }
            }
        }
        // Pop the next node that still begins before the closest hit so far.
        while (sp > 0 && stack[sp - 1].t > tmax)
            --sp;
        if (sp == 0) break;
        ref = stack[--sp].ref;
    }
    if (!best_base) return false;
    std::uint32_t best_ref;
    std::memcpy(&best_ref, best_base + 9 * best_c + best_lane, sizeof best_ref);
    out = BvhAccel::TraceHit{tmax, best_u, best_v, best_ref};
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
