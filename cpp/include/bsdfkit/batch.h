// Array kernels: eval / pdf / sample / albedo of one model over N directions, chunked over a
// thread pool (pool.h). Every element is computed by pure per-element code, so outputs are
// bit-identical for any thread count. Inner loops are written to auto-vectorize.
#pragma once
#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>
#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "core/bsdf.h"
#include "core/bxdf.h"
#include "core/rng.h"
#include "pool.h"

namespace bsdfkit {

inline constexpr int64_t kChunk = 8192;

// Runs fn(begin, end) over fixed chunks of [0, n) on the calling thread and the pool's helpers
// (pool.h). Chunk boundaries never depend on the thread count, which keeps chunk-level
// reductions deterministic too. Returns false if an interrupt (Ctrl-C) stopped it early; the
// outputs are then incomplete.
template <typename Fn> inline bool parallel_chunks(int64_t n, int nthreads, int64_t chunk, const Fn &fn) {
    int64_t nchunks = (n + chunk - 1) / chunk;
    InterruptPoll poll;
    auto body = [&](int64_t c) { fn(c * chunk, std::min(n, (c + 1) * chunk)); };
    return ChunkPool::instance().run(nchunks, nthreads, body, poll);
}

// A direction is accepted if it is finite and unit length to this tolerance on |w|^2.
template <typename F> inline constexpr F kUnitTol = F(1e-4);
template <typename F> constexpr bool unit_accepts(F d) { // d = |w|^2; a NaN fails
    F t = d - F(1);
    return (t < F(0) ? -t : t) <= kUnitTol<F>;
}
// The scalar loops' check: a direction that unit_accepts refuses is counted and replaced by the normal
// (0, 0, 1) before the model sees it. The call then raises ValueError (bindings) and never returns
// the value, but a table model (merl.h, measured.h) must not index its tables with a NaN or an
// infinity first: MERL and Measured read out of bounds and crashed on them (session 23).
template <typename F> inline int64_t check_dir(Vec3<F> *w) {
    if (__builtin_expect(unit_accepts(dot(*w, *w)), 1)) return 0;
    *w = Vec3<F>(F(0), F(0), F(1));
    return 1;
}

template <typename F, int S> inline Vec3<F> load3(const F *p, int64_t i) {
    return Vec3<F>(p[i * S], p[i * S + 1], p[i * S + 2]);
}

// ---- The packet path (models with `Vectorized = true`, core/bxdf.h): the model code runs on
// Packet<F> (core/simd.h), kPacketWidth elements at a time. The array's tail is padded to a
// full packet (with the direction (0, 0, 1) and uniforms 0) and runs through the same vector
// code, so each element's result depends on nothing but its own inputs: bit-identical for any
// array position, chunking and thread count (tests/test_packet_position.py checks). Interleaved
// (N, 3) and (N, 2) arrays are transposed through small aligned buffers (float32 rows of 3 in
// full packets: through register shuffles, below).
template <typename F> inline constexpr int64_t kW = int64_t(kPacketWidth);

// ---- Rows <-> packets by register shuffles (a blocked transpose). The rows are moved in groups
// of G lanes, G = one vector register of F (AVX-512: 16 floats or 8 doubles; otherwise 8
// floats): an (N, 3) group is 3 register loads, each component 2 two-source permutations
// (vpermt2ps / vpermt2pd) away on AVX-512, or 2 blends and 1 permutation on AVX2; (N, 2) pairs
// (the sample kernels' u) 1 permutation per component; rows of 4 (spectral) 3 on AVX-512. The
// groups go straight into the packets' lanes (rows_to_packets below): the earlier 8-lane groups
// went through a stack buffer, and on AVX-512 a zmm load spanning two ymm stores misses
// store-forwarding (14-25 % of the float32 sample kernel on a Sapphire Rapids host, one
// instruction). Pure data movement: the same packets as the scalar
// transposition through a stack buffer, bit for bit. Written in GCC's generic vector
// extensions (__builtin_shuffle; the build's compiler), not in ISA intrinsics; other compilers
// keep the scalar transposition. float64 on AVX2 keeps it too (the shuffles gained nothing on
// Zen 3, session 6).
#if defined(__GNUC__) && !defined(__clang__)
#define BSDFKIT_SHUFFLE_ROWS 1
#define BSDFKIT_SHUF2(T, a, b, ...) __builtin_shuffle(a, b, (T){__VA_ARGS__})
#define BSDFKIT_SHUF1(T, a, ...) __builtin_shuffle(a, (T){__VA_ARGS__})
#else
#define BSDFKIT_SHUFFLE_ROWS 0
#endif
#if BSDFKIT_SHUFFLE_ROWS
namespace detail_rows {
typedef float v8f __attribute__((vector_size(32)));
typedef int v8i __attribute__((vector_size(32)));
template <typename V> struct IndexOf;  // the index vector of a shuffle of V
template <> struct IndexOf<v8f> { using type = v8i; };
// Index vectors built at compile time from a rule lane -> source slot (slots of the two
// operands numbered 0..2L-1), so each layout below is written once for every width.
template <typename VI, typename Fn, size_t... J> constexpr VI make_index(Fn fn, std::index_sequence<J...>) {
    return VI{fn(int(J))...};
}
template <typename V, typename E> inline constexpr int kLanes = int(sizeof(V) / sizeof(E));
#define BSDFKIT_INDEX(V, E, rule) \
    make_index<typename IndexOf<V>::type>([](int e) { return rule; }, std::make_index_sequence<size_t(kLanes<V, E>)>{})
template <typename V, typename E> inline V load_vec(const E *q) {
    V v;
    std::memcpy(&v, q, sizeof(V));
    return v;
}

// (N, 2) pairs: x = the even slots of (a, b), y = the odd ones; 1 permutation each.
template <typename V, typename E> inline void pairs_to_xy(const E *q, V &x, V &y) {
    constexpr int L = kLanes<V, E>;
    V a = load_vec<V>(q), b = load_vec<V>(q + L);
    x = __builtin_shuffle(a, b, BSDFKIT_INDEX(V, E, 2 * e));
    y = __builtin_shuffle(a, b, BSDFKIT_INDEX(V, E, 2 * e + 1));
}

// Rows of 4 (the spectral kernels' wavelengths and f): component k of row j at 4j + k. Loads:
// rows 0..L/2-1 from (a, b) and L/2..L-1 from (c, d), then the halves joined; stores the
// reverse. 3 permutations per component (AVX-512 only: kHasRows4).
template <typename V, typename E> inline void rows4_to_xyzw(const E *q, V (&o)[4]) {
    constexpr int L = kLanes<V, E>;
    V a = load_vec<V>(q), b = load_vec<V>(q + L), c = load_vec<V>(q + 2 * L), d = load_vec<V>(q + 3 * L);
    constexpr auto join = BSDFKIT_INDEX(V, E, e < L / 2 ? e : L + e - L / 2);
    constexpr auto k0 = BSDFKIT_INDEX(V, E, e < L / 2 ? 4 * e : 0);
    constexpr auto k1 = BSDFKIT_INDEX(V, E, e < L / 2 ? 4 * e + 1 : 0);
    constexpr auto k2 = BSDFKIT_INDEX(V, E, e < L / 2 ? 4 * e + 2 : 0);
    constexpr auto k3 = BSDFKIT_INDEX(V, E, e < L / 2 ? 4 * e + 3 : 0);
    o[0] = __builtin_shuffle(__builtin_shuffle(a, b, k0), __builtin_shuffle(c, d, k0), join);
    o[1] = __builtin_shuffle(__builtin_shuffle(a, b, k1), __builtin_shuffle(c, d, k1), join);
    o[2] = __builtin_shuffle(__builtin_shuffle(a, b, k2), __builtin_shuffle(c, d, k2), join);
    o[3] = __builtin_shuffle(__builtin_shuffle(a, b, k3), __builtin_shuffle(c, d, k3), join);
}
// Output vector r, lane e: row j = (r L + e) / 4, component k = e % 4 (L a multiple of 4).
template <int R, typename V, typename E> inline V rows4_out(const V (&v)[4]) {
    constexpr int L = kLanes<V, E>;
    constexpr auto xy = BSDFKIT_INDEX(V, E, e % 4 == 0 ? (R * L + e) / 4 : e % 4 == 1 ? L + (R * L + e) / 4 : 0);
    constexpr auto zw = BSDFKIT_INDEX(V, E, e % 4 == 2 ? (R * L + e) / 4 : e % 4 == 3 ? L + (R * L + e) / 4 : 0);
    constexpr auto pick = BSDFKIT_INDEX(V, E, e % 4 < 2 ? e : L + e);
    return __builtin_shuffle(__builtin_shuffle(v[0], v[1], xy), __builtin_shuffle(v[2], v[3], zw), pick);
}
template <typename V, typename E> inline void xyzw_to_rows4(E *q, const V (&v)[4]) {
    constexpr int L = kLanes<V, E>;
    const V o[4] = {rows4_out<0, V, E>(v), rows4_out<1, V, E>(v), rows4_out<2, V, E>(v), rows4_out<3, V, E>(v)};
    for (int r = 0; r < 4; ++r) std::memcpy(q + r * L, &o[r], sizeof(V));
}

#if defined(__AVX512F__)
typedef float v16f __attribute__((vector_size(64)));
typedef int v16i __attribute__((vector_size(64)));
typedef double v8d __attribute__((vector_size(64)));
typedef long long v8l __attribute__((vector_size(64)));
template <> struct IndexOf<v16f> { using type = v16i; };
template <> struct IndexOf<v8d> { using type = v8l; };
// Rows of 3 with two-source permutations (vpermt2ps / vpermt2pd): component k of row j sits at
// 3j + k of the group's 3L scalars (a, b, c), gathered from (a, b) first, then the lanes past
// 2L from c; the reverse for stores (2 permutations per component).
template <int K, typename V, typename E> inline V rows3_component(const V &a, const V &b, const V &c) {
    constexpr int L = kLanes<V, E>;
    constexpr auto ab = BSDFKIT_INDEX(V, E, 3 * e + K < 2 * L ? 3 * e + K : 0);
    constexpr auto abc = BSDFKIT_INDEX(V, E, 3 * e + K < 2 * L ? e : L + 3 * e + K - 2 * L);
    return __builtin_shuffle(__builtin_shuffle(a, b, ab), c, abc);
}
template <typename V, typename E> inline void rows_to_xyz(const E *q, V &x, V &y, V &z) {
    constexpr int L = kLanes<V, E>;
    V a = load_vec<V>(q), b = load_vec<V>(q + L), c = load_vec<V>(q + 2 * L);
    x = rows3_component<0, V, E>(a, b, c);
    y = rows3_component<1, V, E>(a, b, c);
    z = rows3_component<2, V, E>(a, b, c);
}
// Output vector r, lane e: row j = (r L + e) / 3, component k = (r L + e) % 3: x and y first,
// then z.
template <int R, typename V, typename E> inline V rows3_out(const V &x, const V &y, const V &z) {
    constexpr int L = kLanes<V, E>;
    constexpr auto xy = BSDFKIT_INDEX(V, E, (R * L + e) % 3 == 0 ? (R * L + e) / 3 : (R * L + e) % 3 == 1 ? L + (R * L + e) / 3 : 0);
    constexpr auto xyz = BSDFKIT_INDEX(V, E, (R * L + e) % 3 == 2 ? L + (R * L + e) / 3 : e);
    return __builtin_shuffle(__builtin_shuffle(x, y, xy), z, xyz);
}
// The three registers of rows a group's (x, y, z) make, in memory order.
template <typename V, typename E> inline void xyz_to_row_groups(const V &x, const V &y, const V &z, V (&o)[3]) {
    o[0] = rows3_out<0, V, E>(x, y, z);
    o[1] = rows3_out<1, V, E>(x, y, z);
    o[2] = rows3_out<2, V, E>(x, y, z);
}
template <typename V, typename E> inline void xyz_to_rows(E *q, const V &x, const V &y, const V &z) {
    constexpr int L = kLanes<V, E>;
    V o[3];
    xyz_to_row_groups<V, E>(x, y, z, o);
    for (int r = 0; r < 3; ++r) std::memcpy(q + r * L, &o[r], sizeof(V));
}
template <typename F> using group_t = std::conditional_t<std::is_same_v<F, float>, v16f, v8d>;
template <typename F> inline constexpr bool kHasGroup = true;
template <typename F> inline constexpr bool kHasRows4 = true;
#else
// AVX2 / SSE: float32 in groups of 8, rows of 3 by blends and one permutation per component
// (AVX2 has no two-source permutation). Slots of the three vectors a, b, c (rows 0..7: a = x0
// y0 z0 x1 y1 z1 x2 y2, ...) that hold x, y, z: a {x: 0 3 6, y: 1 4 7, z: 2 5}, b {z: 0 3 6,
// x: 1 4 7, y: 2 5}, c {y: 0 3 6, z: 1 4 7, x: 2 5}. The blends gather one component's slots
// (mx = x0 x3 x6 x1 x4 x7 x2 x5, my, mz); the permutation puts them in order.
inline void rows_to_xyz(const float *q, v8f &x, v8f &y, v8f &z) {
    v8f a = load_vec<v8f>(q), b = load_vec<v8f>(q + 8), c = load_vec<v8f>(q + 16);
    v8f ab_x = BSDFKIT_SHUF2(v8i, a, b, 0, 9, 2, 3, 12, 5, 6, 15), ab_y = BSDFKIT_SHUF2(v8i, a, b, 0, 1, 10, 3, 4, 13, 6, 7),
        ab_z = BSDFKIT_SHUF2(v8i, a, b, 8, 1, 2, 11, 4, 5, 14, 7);
    v8f mx = BSDFKIT_SHUF2(v8i, ab_x, c, 0, 1, 10, 3, 4, 13, 6, 7), my = BSDFKIT_SHUF2(v8i, ab_y, c, 8, 1, 2, 11, 4, 5, 14, 7),
        mz = BSDFKIT_SHUF2(v8i, ab_z, c, 0, 9, 2, 3, 12, 5, 6, 15);
    x = BSDFKIT_SHUF1(v8i, mx, 0, 3, 6, 1, 4, 7, 2, 5);
    y = BSDFKIT_SHUF1(v8i, my, 1, 4, 7, 2, 5, 0, 3, 6);
    z = BSDFKIT_SHUF1(v8i, mz, 2, 5, 0, 3, 6, 1, 4, 7);
}
template <typename V, typename E> inline void xyz_to_row_groups(const V &x, const V &y, const V &z, V (&o)[3]) {
    static_assert(std::is_same_v<V, v8f>, "xyz_to_row_groups: AVX2 groups are 8 floats");
    v8f mx = BSDFKIT_SHUF1(v8i, x, 0, 3, 6, 1, 4, 7, 2, 5), my = BSDFKIT_SHUF1(v8i, y, 5, 0, 3, 6, 1, 4, 7, 2),
        mz = BSDFKIT_SHUF1(v8i, z, 2, 5, 0, 3, 6, 1, 4, 7);
    o[0] = BSDFKIT_SHUF2(v8i, BSDFKIT_SHUF2(v8i, mx, my, 0, 9, 2, 3, 12, 5, 6, 15), mz, 0, 1, 10, 3, 4, 13, 6, 7);
    o[1] = BSDFKIT_SHUF2(v8i, BSDFKIT_SHUF2(v8i, mx, my, 0, 1, 10, 3, 4, 13, 6, 7), mz, 8, 1, 2, 11, 4, 5, 14, 7);
    o[2] = BSDFKIT_SHUF2(v8i, BSDFKIT_SHUF2(v8i, mx, my, 8, 1, 2, 11, 4, 5, 14, 7), mz, 0, 9, 2, 3, 12, 5, 6, 15);
}
inline void xyz_to_rows(float *q, v8f x, v8f y, v8f z) {
    v8f o[3];
    xyz_to_row_groups<v8f, float>(x, y, z, o);
    std::memcpy(q, &o[0], 32);
    std::memcpy(q + 8, &o[1], 32);
    std::memcpy(q + 16, &o[2], 32);
}
template <typename F> using group_t = v8f;
template <typename F> inline constexpr bool kHasGroup = std::is_same_v<F, float>;
template <typename F> inline constexpr bool kHasRows4 = false; // AVX2: the stack transposition
#endif
#undef BSDFKIT_INDEX
} // namespace detail_rows
#endif
// Whether rows of 3 and pairs move through the register shuffles, and the group's lanes.
#if BSDFKIT_SHUFFLE_ROWS
template <typename F> inline constexpr int64_t kGroup = detail_rows::kLanes<detail_rows::group_t<F>, F>;
template <typename F> inline constexpr bool kShuffleRows = detail_rows::kHasGroup<F> && kPacketWidth % kGroup<F> == 0;
#else
template <typename F> inline constexpr bool kShuffleRows = false;
#endif
#if BSDFKIT_SHUFFLE_ROWS
// A full packet's rows (S = 3) or pairs (S = 2) from q, group by group straight into the
// packets' lanes (a packet's lanes are contiguous), and the reverse for rows of 3. No stack
// buffer in between: GCC expands a buffer-to-packet copy into ymm moves, and a zmm load of two
// ymm stores is not store-forwarded (a ~15-cycle stall per packet on AVX-512).
template <typename F> inline void group_into(Packet<F> &dst, int64_t g, const detail_rows::group_t<F> &v) {
    std::memcpy(reinterpret_cast<char *>(&dst) + g * sizeof(F), &v, sizeof(v));
}
template <typename F> inline detail_rows::group_t<F> group_of(const Packet<F> &src, int64_t g) {
    detail_rows::group_t<F> v;
    std::memcpy(&v, reinterpret_cast<const char *>(&src) + g * sizeof(F), sizeof(v));
    return v;
}
template <typename F> inline void rows_to_packets(const F *q, Packet<F> &x, Packet<F> &y, Packet<F> &z) {
    using G = detail_rows::group_t<F>;
    for (int64_t g = 0; g < kW<F>; g += kGroup<F>) {
        G a, b, c;
        detail_rows::rows_to_xyz(q + 3 * g, a, b, c);
        group_into(x, g, a);
        group_into(y, g, b);
        group_into(z, g, c);
    }
}
template <typename F> inline void pairs_to_packets(const F *q, Packet<F> &x, Packet<F> &y) {
    using G = detail_rows::group_t<F>;
    for (int64_t g = 0; g < kW<F>; g += kGroup<F>) {
        G a, b;
        detail_rows::pairs_to_xy(q + 2 * g, a, b);
        group_into(x, g, a);
        group_into(y, g, b);
    }
}
template <typename F> inline void packets_to_rows(F *q, const Packet<F> &x, const Packet<F> &y, const Packet<F> &z) {
    for (int64_t g = 0; g < kW<F>; g += kGroup<F>)
        detail_rows::xyz_to_rows(q + 3 * g, group_of(x, g), group_of(y, g), group_of(z, g));
}
#endif

// Lanes [i, i + cnt) of an (N, S) array (S = 3 or 2; S = 0: one broadcast row of 3) as C
// packets; lanes past cnt hold `pad`.
template <int S, int C, typename F>
inline void load_lanes(const F *p, int64_t i, int64_t cnt, const F (&pad)[C], Packet<F> (&out)[C]) {
    using P = Packet<F>;
    constexpr int64_t W = kW<F>;
    if constexpr (S == 0) {
        for (int c = 0; c < C; ++c) out[c] = P(p[c]);
    } else {
        static_assert(S == C, "load_lanes: row width");
        alignas(64) F tail[S * W];
        alignas(64) F soa[C][W];
        const F *q = p + S * i;
#if BSDFKIT_SHUFFLE_ROWS
        if constexpr ((S == 3 || S == 2) && kShuffleRows<F>) {
            if (cnt == W) {
                if constexpr (S == 3) rows_to_packets(q, out[0], out[1], out[2]);
                else pairs_to_packets(q, out[0], out[1]);
                return;
            }
        }
        if constexpr (S == 4 && kShuffleRows<F> && detail_rows::kHasRows4<F>) {
            if (cnt == W) {
                for (int64_t g = 0; g < W; g += kGroup<F>) {
                    detail_rows::group_t<F> v[4];
                    detail_rows::rows4_to_xyzw(q + 4 * g, v);
                    for (int c = 0; c < 4; ++c) group_into(out[c], g, v[c]);
                }
                return;
            }
        }
#endif
        if (cnt < W) {
            for (int64_t j = 0; j < S * W; ++j) tail[j] = j < S * cnt ? q[j] : pad[j % S];
            q = tail;
        }
        for (int64_t j = 0; j < W; ++j)
            for (int c = 0; c < C; ++c) soa[c][j] = q[S * j + c];
        for (int c = 0; c < C; ++c) out[c] = drjit::load_aligned<P>(soa[c]);
    }
}
template <int S, typename F> inline Vec3<Packet<F>> load3_lanes(const F *p, int64_t i, int64_t cnt) {
#if BSDFKIT_SHUFFLE_ROWS
    if constexpr (S == 3 && kShuffleRows<F>) {
        if (cnt == kW<F>) {
            Vec3<Packet<F>> r;
            rows_to_packets(p + 3 * i, r.x, r.y, r.z);
            return r;
        }
    }
#endif
    static constexpr F pad[3] = {F(0), F(0), F(1)};
    Packet<F> v[3];
    load_lanes<S, 3>(p, i, cnt, pad, v);
    return Vec3<Packet<F>>(v[0], v[1], v[2]);
}
// Lanes [i, i + cnt) of a contiguous array; past cnt, pad.
template <typename F> inline Packet<F> load1_lanes(const F *p, int64_t i, int64_t cnt, F pad) {
    using P = Packet<F>;
    if (cnt == kW<F>) return drjit::load<P>(p + i);
    alignas(64) F t[kW<F>];
    for (int64_t j = 0; j < kW<F>; ++j) t[j] = j < cnt ? p[i + j] : pad;
    return drjit::load_aligned<P>(t);
}
// Stores the first cnt lanes of C packets as rows [i, i + cnt) of an (N, C) array.
template <int C, typename F> inline void store_lanes(F *p, int64_t i, int64_t cnt, const Packet<F> (&v)[C]) {
    constexpr int64_t W = kW<F>;
    F *q = p + C * i;
#if BSDFKIT_SHUFFLE_ROWS
    if constexpr (C == 3 && kShuffleRows<F>) {
        if (cnt == W) {
            packets_to_rows(q, v[0], v[1], v[2]);
            return;
        }
    }
    if constexpr (C == 4 && kShuffleRows<F> && detail_rows::kHasRows4<F>) {
        if (cnt == W) {
            for (int64_t g = 0; g < W; g += kGroup<F>) {
                const detail_rows::group_t<F> x[4] = {group_of(v[0], g), group_of(v[1], g), group_of(v[2], g),
                                                      group_of(v[3], g)};
                detail_rows::xyzw_to_rows4(q + 4 * g, x);
            }
            return;
        }
    }
#endif
    alignas(64) F soa[C][W];
    for (int c = 0; c < C; ++c) drjit::store_aligned(soa[c], v[c]);
    if (cnt == W) {
        for (int64_t j = 0; j < W; ++j)
            for (int c = 0; c < C; ++c) q[C * j + c] = soa[c][j];
    } else {
        for (int64_t j = 0; j < cnt; ++j)
            for (int c = 0; c < C; ++c) q[C * j + c] = soa[c][j];
    }
}
template <typename F> inline void store3_lanes(F *p, int64_t i, int64_t cnt, const Spectrum<Packet<F>> &s) {
    const Packet<F> v[3] = {s[0], s[1], s[2]};
    store_lanes<3>(p, i, cnt, v);
}
template <typename F> inline void store3_lanes(F *p, int64_t i, int64_t cnt, const Vec3<Packet<F>> &w) {
    const Packet<F> v[3] = {w.x, w.y, w.z};
    store_lanes<3>(p, i, cnt, v);
}
template <typename F> inline void store1_lanes(F *p, int64_t i, int64_t cnt, const Packet<F> &v) {
    if (cnt == kW<F>) {
        drjit::store(p + i, v);
    } else {
        alignas(64) F t[kW<F>];
        drjit::store_aligned(t, v);
        for (int64_t j = 0; j < cnt; ++j) p[i + j] = t[j];
    }
}
// unit_accepts' accepted |w|^2 as a closed range [lo, hi] of F, exactly the values it accepts
// (d - 1 is exact near 1, Sterbenz), found by stepping from 1 -+ kUnitTol one ulp at a time
// (ulp 2^-p below 1, 2^-(p-1) above): the packets test it on the bits of |w|^2 (UnitKey below),
// one comparison per direction instead of a subtraction, an absolute value and a comparison.
template <typename F> struct UnitRange {
    F lo, hi;
};
template <typename F> constexpr UnitRange<F> make_unit_range() {
    constexpr F below = std::numeric_limits<F>::epsilon() / F(2), above = std::numeric_limits<F>::epsilon();
    F lo = F(1) - kUnitTol<F>, hi = F(1) + kUnitTol<F>;
    while (!unit_accepts(lo)) lo += below;
    while (unit_accepts(lo - below)) lo -= below;
    while (!unit_accepts(hi)) hi -= above;
    while (unit_accepts(hi + above)) hi += above;
    return {lo, hi};
}
template <typename F> inline constexpr UnitRange<F> kUnitRange = make_unit_range<F>();
static_assert(!unit_accepts(kUnitRange<float>.lo - std::numeric_limits<float>::epsilon() / 2) &&
                  unit_accepts(kUnitRange<float>.lo) && unit_accepts(kUnitRange<float>.hi) &&
                  !unit_accepts(kUnitRange<float>.hi + std::numeric_limits<float>::epsilon()),
              "kUnitRange: the range's ends");
static_assert(!unit_accepts(kUnitRange<double>.lo - std::numeric_limits<double>::epsilon() / 2) &&
                  unit_accepts(kUnitRange<double>.lo) && unit_accepts(kUnitRange<double>.hi) &&
                  !unit_accepts(kUnitRange<double>.hi + std::numeric_limits<double>::epsilon()),
              "kUnitRange: the range's ends");

// The number of lanes where `pass` is false. Failures are rare, so the common case is one mask
// test and a predicted branch (a per-packet mask-to-integer popcount cost 4 more instructions on
// the vector ports' side of the machine: +4-7 % on the pdf kernels).
template <typename M> inline int64_t count_failed(const M &pass) {
    if (__builtin_expect(drjit::all(pass), 1)) return 0;
    return int64_t(drjit::count(!pass));
}
// The packets' unit check on the bits of d = |w|^2 (I: the signed integer as wide as F). A
// non-negative float's bits grow with it, so lo <= d <= hi exactly when bits(d) - bits(lo)
// (wrapping) <= span = bits(hi) - bits(lo), and a negative d (sign bit set) or a NaN (exponent all
// ones, above hi's) lands far above span. Shifted by 2^(w-1), that unsigned test is the signed
// one key(d) = bits(d) - c <= limit (c = bits(lo) + 2^(w-1), limit = INT_MIN + span; Dr.Jit's
// integer comparisons are signed): one subtraction and one comparison per direction, and one
// comparison of the maximum key for a pair (eval / pdf), where the float range took two
// comparisons and a mask and per direction.
template <typename F> struct UnitKey {
    using I = std::conditional_t<sizeof(F) == 4, int32_t, int64_t>;
    using U = std::make_unsigned_t<I>;
    static constexpr U sign = U(1) << (8 * sizeof(U) - 1);
    static constexpr U lo_bits = __builtin_bit_cast(U, kUnitRange<F>.lo), hi_bits = __builtin_bit_cast(U, kUnitRange<F>.hi);
    static constexpr I c = __builtin_bit_cast(I, U(lo_bits + sign));
    static constexpr I limit = __builtin_bit_cast(I, U(sign + (hi_bits - lo_bits)));
    // the scalar form of the packets' test, for the checks below
    static constexpr bool accepts(F d) { return __builtin_bit_cast(I, U(__builtin_bit_cast(U, d) - U(c))) <= limit; }
};
template <typename F> constexpr bool unit_key_agrees(F d) { return UnitKey<F>::accepts(d) == unit_accepts(d); }
template <typename F> constexpr bool unit_key_checks() {
    constexpr F lo = kUnitRange<F>.lo, hi = kUnitRange<F>.hi, e = std::numeric_limits<F>::epsilon();
    constexpr F inf = std::numeric_limits<F>::infinity();
    return unit_key_agrees(lo) && unit_key_agrees(hi) && unit_key_agrees(F(lo - e / 2)) && unit_key_agrees(F(hi + e)) &&
           unit_key_agrees(F(1)) && unit_key_agrees(F(0)) && unit_key_agrees(F(-0.0)) && unit_key_agrees(F(-1)) &&
           unit_key_agrees(inf) && unit_key_agrees(-inf) && unit_key_agrees(std::numeric_limits<F>::quiet_NaN()) &&
           unit_key_agrees(F(-std::numeric_limits<F>::quiet_NaN())) && unit_key_agrees(std::numeric_limits<F>::max()) &&
           unit_key_agrees(std::numeric_limits<F>::denorm_min()) && unit_key_agrees(F(2)) && unit_key_agrees(F(0.5));
}
static_assert(unit_key_checks<float>() && unit_key_checks<double>(), "UnitKey: the bits test is unit_accepts'");
template <typename F> using UnitKeys = Packet<typename UnitKey<F>::I>;
template <typename F> inline UnitKeys<F> unit_key(const Vec3<Packet<F>> &w) {
    return drjit::reinterpret_array<UnitKeys<F>>(dot(w, w)) - UnitKeys<F>(UnitKey<F>::c);
}
template <typename F> inline auto unit_key_ok(const UnitKeys<F> &k) { return k <= UnitKeys<F>(UnitKey<F>::limit); }
// Lanes that unit_accepts refuses (the padding is unit length).
template <typename F> inline int64_t count_not_unit(const Vec3<Packet<F>> &w) {
    return count_failed(unit_key_ok<F>(unit_key(w)));
}
// The same for a pair: one test of both keys' maximum; only a packet that fails it counts each.
template <typename F>
inline void count_not_unit_pair(const Vec3<Packet<F>> &o, const Vec3<Packet<F>> &w, int64_t *bo, int64_t *bi) {
    UnitKeys<F> ko = unit_key(o), ki = unit_key(w);
    if (__builtin_expect(drjit::all(unit_key_ok<F>(drjit::maximum(ko, ki))), 1)) return;
    *bo += count_failed(unit_key_ok<F>(ko));
    *bi += count_failed(unit_key_ok<F>(ki));
}

struct BadCounts {
    std::atomic<int64_t> wo{0}, wi{0}, uc{0}, u{0};  // bad directions; uniforms outside [0, 1] or NaN
};

// Uniforms in [b, e) outside [0, 1] or NaN (a NaN fails both comparisons). The sample kernel
// still maps every uniform into [0, 1) (clamp_uniform); the bindings turn a count into a ValueError.
template <typename F> inline int64_t count_bad_uniforms(const F *p, int64_t b, int64_t e) {
    int64_t c = 0;
    for (int64_t i = b; i < e; ++i) c += !((p[i] >= F(0)) & (p[i] <= F(1)));
    return c;
}

// ---- Direction arrays as the packet path reads them. S (a template argument) is 3 for rows
// (an (N, 3) C-order array: x y z interleaved, transposed to packets through load3_lanes), 0
// for one broadcast direction, kPlanesLayout for planes, and kAnyLayout for a layout known only at
// run time (Dirs::layout; one instantiation of the model code then serves every combination, the
// layout being a branch per packet that every lane shares). Planes (structure of arrays, what
// Mitsuba's kernels read: an (N, 3) Fortran-order array, i.e. the x, y and z components each
// contiguous, `plane` elements apart) load as three packet loads, no transposition.
enum class DirLayout : uint8_t { Rows, One, Planes };
inline constexpr int kAnyLayout = -1;
inline constexpr int kPlanesLayout = -2;
template <typename F> struct Dirs {
    const F *p;
    DirLayout layout;
    int64_t plane = 0; // Planes: elements between the x, y and z planes (the array's N)
};

// Lanes [i, i + cnt) of three component planes; past cnt, the direction (0, 0, 1).
template <typename F> inline Vec3<Packet<F>> load3_planes(const F *p, int64_t plane, int64_t i, int64_t cnt) {
    return Vec3<Packet<F>>(load1_lanes(p, i, cnt, F(0)), load1_lanes(p + plane, i, cnt, F(0)),
                           load1_lanes(p + 2 * plane, i, cnt, F(1)));
}
template <int S, typename F> inline Vec3<Packet<F>> load_dirs(const Dirs<F> &d, int64_t i, int64_t cnt) {
    if constexpr (S == kPlanesLayout) {
        return load3_planes(d.p, d.plane, i, cnt);
    } else if constexpr (S != kAnyLayout) {
        return load3_lanes<S>(d.p, i, cnt);
    } else {
        if (d.layout == DirLayout::Planes) return load3_planes(d.p, d.plane, i, cnt);
        if (d.layout == DirLayout::One) return load3_lanes<0>(d.p, i, cnt);
        return load3_lanes<3>(d.p, i, cnt);
    }
}
template <int S, typename F> inline bool is_one(const Dirs<F> &d) {
    if constexpr (S == kAnyLayout) return d.layout == DirLayout::One;
    else return S == 0;
}
template <int S, typename F> inline Dirs<F> dirs_of(const F *p) {
    return {p, S == 0 ? DirLayout::One : DirLayout::Rows, 0};
}
// The same directions from element h on (one broadcast direction stays itself).
template <typename F> inline Dirs<F> shifted(const Dirs<F> &d, int64_t h) {
    Dirs<F> r = d;
    if (d.layout == DirLayout::Rows) r.p += 3 * h;
    else if (d.layout == DirLayout::Planes) r.p += h;
    return r;
}

// ---- Software prefetch of the streamed inputs, kPrefetchAhead elements ahead of the packet
// loop (within its chunk), every 64-byte line of the packet's rows (prefetcht0). A hint: it
// never faults and changes no result. Measured on an AMD EPYC Zen 4 host (C++ harness over
// these loops, N = 1e6, medians of 3 alternating runs, TSC cycles per packet of 16), where the
// hardware prefetchers alone left the light kernels well below a plain read + write stream:
// pdf 1 thread Diffuse 44 -> 30, Conductor rough 40 -> 37, Plastic smooth 48 -> 45; 2 threads
// Diffuse 25 -> 15, Plastic smooth 25 -> 23; eval mostly within the noise (Plastic rough -6 %:
// the 6 prefetches per packet are instructions too, in a compute-bound loop). Distance 128-384
// tried (256 best), prefetch to L2 only (t1 / t2: slower), and one line per packet instead of
// every line (slower than none).
inline constexpr int64_t kPrefetchAhead = 256;
// Calls below this many elements keep their inputs in L2 (1 MiB per Zen 4 core: 65536 (N, 3)
// float32 rows are 768 KiB per direction) and skip the prefetches, which there are only
// instructions (0-6 % on the lightest in-cache kernels, tools/perf/loop_ab.py --n 16384).
inline constexpr int64_t kPrefetchMinN = int64_t(1) << 16;
// The 64-byte lines of [p, p + bytes).
inline void prefetch_span(const void *p, size_t bytes) {
    const char *c = static_cast<const char *>(p);
    for (size_t o = 0; o < bytes; o += 64) __builtin_prefetch(c + o, 0, 3);
}
// The lanes [j, j + kW) of a direction array, as its layout stores them.
template <int S, typename F> inline void prefetch_dirs(const Dirs<F> &d, int64_t j) {
    constexpr size_t B = sizeof(F) * size_t(kW<F>);
    if constexpr (S == 3) {
        prefetch_span(d.p + 3 * j, 3 * B);
    } else if constexpr (S == kPlanesLayout) {
        for (int c = 0; c < 3; ++c) prefetch_span(d.p + c * d.plane + j, B);
    } else if constexpr (S == kAnyLayout) {
        if (d.layout == DirLayout::Rows) prefetch_span(d.p + 3 * j, 3 * B);
        else if (d.layout == DirLayout::Planes)
            for (int c = 0; c < 3; ++c) prefetch_span(d.p + c * d.plane + j, B);
    }
}

// ---- Non-temporal stores of a large call's outputs. A plain store to a line that is not in
// cache first reads it (read for ownership): a kernel whose outputs exceed the caches moves its
// output bytes twice. A streaming store (vmovntps / vmovntpd) writes a whole 64-byte line
// without reading it and leaves it out of the caches (and the call's inputs in them). From
// kStreamMinBytes of a call's traffic (inputs + outputs) on, about half this host's 32 MiB
// L3 (Zen 4): Diffuse pdf at N = 1e6 (28 MB) streamed gained 1.08-1.16x. Only whole, aligned
// lines: an output array that starts on a line (bsdfkit's own result arrays do) has every full
// packet's rows on whole lines, as chunks start at multiples of kChunk. Values are unchanged:
// only how they are stored. AVX-512 and AVX2 float32 with GCC's vector extensions (the register
// groups above); elsewhere plain stores.
// Only models whose line in the policy table (batch_policy.h, with the measurements) says
// stream_outputs stream: the kernels limited by memory traffic. Streaming is not the default: the
// second instantiation of a heavy loop compiles or places differently (Hair eval's plain loop
// itself runs at 364 or 406 cycles per packet depending on the program around it). Realigning unaligned outputs in registers (one permutation per
// line, the previous packet's last group carried in a register across the loop) gained as much
// on Diffuse eval but cost its sampler 7 % (four carries spilled), so unaligned outputs are
// stored plainly; since session 28 an eval / pdf output off a line has its first rows (up to
// a packet, line_head) stored plainly and the rest, from a line, streamed.
#if BSDFKIT_SHUFFLE_ROWS && (defined(__AVX512F__) || defined(__AVX2__))
#define BSDFKIT_STREAM_STORES 1
#else
#define BSDFKIT_STREAM_STORES 0
#endif
inline constexpr int64_t kStreamMinBytes = int64_t(16) << 20;
// Whether a call that reads and writes `traffic` bytes in all is large enough to stream its
// outputs (the model's trait streams_outputs is the other condition).
inline bool big_enough_to_stream(int64_t traffic) { return BSDFKIT_STREAM_STORES && traffic >= kStreamMinBytes; }
template <typename F> inline constexpr bool kStreams = BSDFKIT_STREAM_STORES && kShuffleRows<F>;
// The sample kernel streams on AVX-512 only: its AVX2 build ran 0.87-0.92x with streaming (Zen 4,
// -march=znver3, N = 1e6; its eval / pdf 1.04-1.11x).
#if defined(__AVX512F__)
template <typename F> inline constexpr bool kStreamSamples = kStreams<F>;
#else
template <typename F> inline constexpr bool kStreamSamples = false;
#endif
// streams_outputs<M>, streams_samples<M> and instance_streams(m): the policy table
// (batch_policy.h, included through core/simd.h).
inline bool on_line(const void *p) { return (reinterpret_cast<uintptr_t>(p) & 63) == 0; }
// The elements before rows of C values of F from p on start on a 64-byte line: the smallest h in
// [0, kW) with p + C h on a line, or -1 if none (p not aligned to F). Every multiple of sizeof(F)
// is reached: C h sizeof(F) mod 64 takes each of those values once for h < 64 / sizeof(F) <= kW
// (C = 1 or 3, odd). A call whose output is off a line (numpy's own arrays start 16 bytes past
// one) runs its first h elements plainly and the rest, from a line, with streaming stores.
template <typename F> inline int64_t line_head(const F *p, int C) {
    const uintptr_t a = reinterpret_cast<uintptr_t>(p);
    for (int64_t h = 0; h < kW<F>; ++h)
        if (((a + uintptr_t(C * h) * sizeof(F)) & 63) == 0) return h;
    return -1;
}

#if BSDFKIT_STREAM_STORES
// One register group at q (aligned to its size), streamed: a whole 64-byte line on AVX-512, half
// of one on AVX2 (a packet's rows fill whole lines either way; the write-combining buffer joins
// the halves).
template <typename F> inline void stream_line(F *q, const detail_rows::group_t<F> &v) {
#if defined(__AVX512F__)
    if constexpr (std::is_same_v<F, float>) _mm512_stream_ps(q, (__m512)v);
    else _mm512_stream_pd(q, (__m512d)v);
#else
    static_assert(std::is_same_v<F, float>, "stream_line: AVX2 groups are float32 (kShuffleRows)");
    _mm256_stream_ps(q, (__m256)v);
#endif
}
#endif

// One float output of a packet loop, rows of C = 1 or 3 from p on. Each chunk writes through a
// writer() of its own (the pointer copied into the chunk), packet by packet: put(i, cnt, value).
// Stream = false: plain stores (store_lanes / store1_lanes), exactly the code of a loop without
// streaming; the kernels instantiate their loops both ways and pick one per call (a run-time
// choice inside one loop cost up to 35 % in cache on the light kernels, and both loops inlined
// in one chunk function 3-8 %; session 21). Stream = true streams a full packet's rows when p is
// on a line (Aligned: the caller checked), else stores them plainly.
template <typename F, int C, bool Stream, bool Aligned = false> struct RowsOut {
    static_assert(C == 1 || C == 3, "RowsOut: rows of 1 or 3");
    static constexpr bool kStream = Stream && kStreams<F>;
    F *p;

    class Writer {
        F *const p_;     // a copy: it then cannot alias the outputs
        const bool on_;  // kStream and p on a line
    public:
        explicit Writer(F *p) : p_(p), on_(kStream && (Aligned || on_line(p))) {}
        void put(int64_t i, int64_t cnt, const Packet<F> (&v)[C]) const {
#if BSDFKIT_STREAM_STORES
            if constexpr (kStream) {
                using G = detail_rows::group_t<F>;
                constexpr int64_t L = kGroup<F>;
                if (on_ && cnt == kW<F>) {  // the packet's rows fill whole lines: i is a multiple of kW
                    F *q = p_ + C * i;
                    for (int64_t g = 0; g < kW<F>; g += L) {
                        if constexpr (C == 3) {
                            G r[3];
                            detail_rows::xyz_to_row_groups<G, F>(group_of(v[0], g), group_of(v[1], g), group_of(v[2], g), r);
                            for (int k = 0; k < 3; ++k) stream_line(q + 3 * g + k * L, r[k]);
                        } else {
                            stream_line(q + g, group_of(v[0], g));
                        }
                    }
                    return;
                }
            }
#endif
            if constexpr (C == 1) store1_lanes(p_, i, cnt, v[0]);
            else store_lanes<C>(p_, i, cnt, v);
        }
        void put(int64_t i, int64_t cnt, const Spectrum<Packet<F>> &s) const {
            static_assert(C == 3, "RowsOut: a spectrum is 3 channels");
            const Packet<F> v[3] = {s[0], s[1], s[2]};
            put(i, cnt, v);
        }
        void put(int64_t i, int64_t cnt, const Vec3<Packet<F>> &w) const {
            static_assert(C == 3, "RowsOut: a direction is 3 channels");
            const Packet<F> v[3] = {w.x, w.y, w.z};
            put(i, cnt, v);
        }
        void put(int64_t i, int64_t cnt, const Packet<F> &x) const {
            static_assert(C == 1, "RowsOut: one channel");
            const Packet<F> v[1] = {x};
            put(i, cnt, v);
        }
    };
    Writer writer() const { return Writer(p); }
};
// Streaming stores are weakly ordered: a fence before a chunk's end is published to the
// thread that waits for it (pool.h's completion count).
template <bool Streamed> inline void stream_fence() {
#if BSDFKIT_STREAM_STORES
    if constexpr (Streamed) _mm_sfence();
#endif
}

// An output that store(i, cnt, value) writes (plain stores), for pair_packet_loop.
template <typename Store> struct StoreOut {
    static constexpr bool kStream = false;
    Store store;
    struct Writer {
        const Store st;  // a copy, as RowsOut's pointer
        template <typename V> void put(int64_t i, int64_t cnt, const V &v) const { st(i, cnt, v); }
    };
    Writer writer() const { return Writer{store}; }
};
template <typename Store> inline StoreOut<Store> store_out(const Store &s) { return {s}; }

// eval's f as three component planes `plane` elements apart (an (N, 3) Fortran-order array),
// each plane a RowsOut<F, 1, Stream> of its own (streamed where that plane starts on a line).
template <typename F, bool Stream> struct PlanesOut {
    using Plane = RowsOut<F, 1, Stream>;
    static constexpr bool kStream = Plane::kStream;
    F *p;
    int64_t plane;
    struct Writer {
        const typename Plane::Writer w[3];
        void put(int64_t i, int64_t cnt, const Spectrum<Packet<F>> &v) const {
            for (int c = 0; c < 3; ++c) w[c].put(i, cnt, v[c]);
        }
    };
    Writer writer() const {
        return Writer{{Plane{p}.writer(), Plane{p + plane}.writer(), Plane{p + 2 * plane}.writer()}};
    }
};

// A per-chunk local copy of the model's trivially copyable kernel (core/bxdf.h: the model, or
// its `Kernel` base when it holds a shared table): its parameters then cannot alias the outputs,
// so they stay in registers instead of being reloaded, and alias-checked, every iteration.
// Beside it each chunk declares DenormalsFlushedFor<Model> (core/simd.h): FTZ | DAZ for the chunk
// where the model declares FlushDenormals, nothing otherwise.
template <typename Model> using LocalModel = const KernelOf_t<Model>;

// The packet loop of eval and pdf: per chunk a local model, per packet the pair (wo, wi) loaded
// and its non-unit directions counted, then compute(model, wo, wi) written to lanes [i, i + cnt)
// of `out` (a RowsOut, or store_out's plain stores). compute also gets (i, cnt): the spectral
// kernels load their wavelengths with them.
template <int SO, int SI, typename Model, typename F, typename Out, typename Compute>
void pair_packet_loop(const Model &m, const Dirs<F> &wo, const Dirs<F> &wi, int64_t n, int nthreads, BadCounts &bad,
                      const Out &out, const Compute &compute) {
    const bool prefetch = n >= kPrefetchMinN;
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) __attribute__((flatten)) {
        int64_t bo = 0, bi = 0;
        const DenormalsFlushedFor<Model> ftz;
        LocalModel<Model> mloc = m;
        // A local copy of the closure too: the arguments it captures by value (mode, sample
        // flags) then cannot alias the outputs, so their loads and the flag mask leave the loop.
        const Compute cp = compute;
        const auto wr = out.writer();
        // Planes: local copies of the direction arrays' descriptors too, which the outputs' stores
        // cannot alias, so their pointers and plane strides stay in registers (the planes' eval
        // 1.1-1.2x, pdf 1.0-1.6x in cache on Zen 4). Rows read the captured descriptors as before:
        // even a local reference to them changed GCC's code for the light rows kernels, 0.88x.
        constexpr bool local = SO == kPlanesLayout && SI == kPlanesLayout;
        const Dirs<F> cwo = wo, cwi = wi;
        const int64_t pf_end = prefetch ? e : b;  // prefetch while i + kPrefetchAhead + kW <= pf_end
        for (int64_t i = b; i < e; i += kW<F>) {
            int64_t cnt = std::min(kW<F>, e - i);
            if (i + kPrefetchAhead + kW<F> <= pf_end) {
                prefetch_dirs<SO>(local ? cwo : wo, i + kPrefetchAhead);
                prefetch_dirs<SI>(local ? cwi : wi, i + kPrefetchAhead);
            }
            Vec3<Packet<F>> o = load_dirs<SO>(local ? cwo : wo, i, cnt), w = load_dirs<SI>(local ? cwi : wi, i, cnt);
            count_not_unit_pair(o, w, &bo, &bi);
            wr.put(i, cnt, cp(mloc, o, w, i, cnt));
        }
        stream_fence<Out::kStream>();
        // A broadcast direction was counted once per packet lane: once per element is meant.
        bad.wo += is_one<SO>(wo) ? (bo > 0 ? e - b : 0) : bo;
        bad.wi += is_one<SI>(wi) ? (bi > 0 ? e - b : 0) : bi;
    });
}

// The per-element loop of eval and pdf for models without packet code (layered.h, measured.h and
// merl.h say why they stay scalar): as pair_packet_loop, one element at a time; store(model, wo,
// wi, i) computes and writes element i.
template <int SO, int SI, typename Model, typename F, typename Store>
void pair_scalar_loop(const Model &m, const F *wo, const F *wi, int64_t n, int nthreads, BadCounts &bad,
                      const Store &store) {
    parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) __attribute__((flatten)) {
        int64_t bo = 0, bi = 0;
        const DenormalsFlushedFor<Model> ftz;
        LocalModel<Model> mloc = m;
        const Store st = store;
        for (int64_t i = b; i < e; ++i) {
            Vec3<F> o = load3<F, SO>(wo, i), w = load3<F, SI>(wi, i);
            bo += check_dir(&o);
            bi += check_dir(&w);
            st(mloc, o, w, i);
        }
        bad.wo += bo;
        bad.wi += bi;
    });
}

// pair_packet_loop writing rows of C to out; streamed (RowsOut<..., true>) in a call over two
// full direction arrays whose bytes read and written reach kStreamMinBytes, out on a line.
// pair_packet_loop writing `plain`, or, where the model and the call stream (two full direction
// arrays plus `outputs` floats per element reach kStreamMinBytes), streaming from element h on
// (line_head: the first whose output starts on a line; -1: none, plain), the h before it through
// `plain` in a call of their own; streamed(h) is the stream-storing output from element h.
template <int SO, int SI, typename Model, typename F, typename MakeStreamed, typename Plain, typename Compute>
void stream_or_plain_loop(const Model &m, const Dirs<F> &wo, const Dirs<F> &wi, int64_t n, int nthreads,
                          BadCounts &bad, int outputs, int64_t h, const MakeStreamed &streamed, const Plain &plain,
                          const Compute &compute) {
    if constexpr (kStreams<F> && streams_outputs<Model>::value) {
        if (big_enough_to_stream((6 + outputs) * n * int64_t(sizeof(F))) && h >= 0 && instance_streams(m)) {
            if (h > 0) pair_packet_loop<SO, SI>(m, wo, wi, h, 1, bad, plain, compute);
            pair_packet_loop<SO, SI>(m, shifted(wo, h), shifted(wi, h), n - h, nthreads, bad, streamed(h), compute);
            return;
        }
    }
    pair_packet_loop<SO, SI>(m, wo, wi, n, nthreads, bad, plain, compute);
}

template <int SO, int SI, int C, typename Model, typename F, typename Compute>
void pair_rows_loop(const Model &m, const F *wo, const F *wi, int64_t n, F *out, int nthreads, BadCounts &bad,
                    const Compute &compute) {
    const Dirs<F> dwo = dirs_of<SO>(wo), dwi = dirs_of<SI>(wi);
    if constexpr (SO == 3 && SI == 3) {
        stream_or_plain_loop<SO, SI>(m, dwo, dwi, n, nthreads, bad, C, line_head(out, C),
                                     [out](int64_t h) { return RowsOut<F, C, true, true>{out + C * h}; },
                                     RowsOut<F, C, false>{out}, compute);
    } else {
        pair_packet_loop<SO, SI>(m, dwo, dwi, n, nthreads, bad, RowsOut<F, C, false>{out}, compute);
    }
}

// f(wo, wi) for N pairs; SO / SI are 3 for a full array, 0 for one broadcast direction.

template <int SO, int SI, typename Model, typename F>
void eval_batch(const Model &m, const F *wo, const F *wi, int64_t n, TransportMode mode, F *out, int nthreads,
                BadCounts &bad) {
    if constexpr (is_vectorized<Model>::value) {
        pair_rows_loop<SO, SI, 3>(m, wo, wi, n, out, nthreads, bad,
                                  [mode](const auto &mm, const auto &o, const auto &w, int64_t, int64_t) {
                                      return bsdf_f(mm, o, w, mode);
                                  });
        return;
    }
    pair_scalar_loop<SO, SI>(m, wo, wi, n, nthreads, bad,
                             [out, mode](const auto &mm, const Vec3<F> &o, const Vec3<F> &w, int64_t i) {
                                 Spectrum<F> v = bsdf_f(mm, o, w, mode);
                                 out[3 * i] = v[0];
                                 out[3 * i + 1] = v[1];
                                 out[3 * i + 2] = v[2];
                             });
}

template <int SO, int SI, typename Model, typename F>
void pdf_batch(const Model &m, const F *wo, const F *wi, int64_t n, TransportMode mode, uint8_t sf, F *out,
               int nthreads, BadCounts &bad) {
    if constexpr (is_vectorized<Model>::value) {
        pair_rows_loop<SO, SI, 1>(m, wo, wi, n, out, nthreads, bad,
                                  [mode, sf](const auto &mm, const auto &o, const auto &w, int64_t, int64_t) {
                                      return bsdf_pdf(mm, o, w, mode, sf);
                                  });
        return;
    }
    pair_scalar_loop<SO, SI>(m, wo, wi, n, nthreads, bad,
                             [out, mode, sf](const auto &mm, const Vec3<F> &o, const Vec3<F> &w, int64_t i) {
                                 out[i] = bsdf_pdf(mm, o, w, mode, sf);
                             });
}

// eval / pdf on the packet path with the layouts chosen at run time (Dirs), for inputs that are
// not all rows: planes (SoA) read without transposition. eval writes f as rows (out_plane = 0)
// or as three planes out_plane elements apart. The same model code and packets as
// eval_batch / pdf_batch, so the values are bit-identical to theirs for any layout. The SoA call
// (both directions as planes, and eval's f as planes) has loops of its own with the layout known
// at compile time, whose outputs stream as pair_rows_loop's rows do (a model with StreamOutputs,
// a call whose bytes reach kStreamMinBytes, out on a line): through the run-time layout path,
// with its per-packet layout branches and plain stores, planes ran slower than rows on Zen 4
// (SoA / rows 0.77-0.91x for Diffuse, tools/perf/results/RESULTS_zen4.md of session 23). Other mixes take the
// run-time layout path, with plain stores.
// The SoA call's loop: stream_or_plain_loop on planes, streaming from the first element whose first
// output plane starts on a line.
template <typename Model, typename F, typename MakeStreamed, typename Plain, typename Compute>
void planes_pair_loop(const Model &m, const Dirs<F> &wo, const Dirs<F> &wi, int64_t n, int nthreads, BadCounts &bad,
                      const F *out, int outputs, const MakeStreamed &streamed, const Plain &plain,
                      const Compute &compute) {
    stream_or_plain_loop<kPlanesLayout, kPlanesLayout>(m, wo, wi, n, nthreads, bad, outputs, line_head(out, 1),
                                                       streamed, plain, compute);
}
template <typename Model, typename F>
void eval_batch_dirs(const Model &m, const Dirs<F> &wo, const Dirs<F> &wi, int64_t n, TransportMode mode, F *out,
                     int64_t out_plane, int nthreads, BadCounts &bad) {
    static_assert(is_vectorized<Model>::value, "eval_batch_dirs: a packet model (Vectorized = true)");
    const auto f = [mode](const auto &mm, const auto &o, const auto &w, int64_t, int64_t) { return bsdf_f(mm, o, w, mode); };
    if (wo.layout == DirLayout::Planes && wi.layout == DirLayout::Planes && out_plane != 0) {
        planes_pair_loop(m, wo, wi, n, nthreads, bad, out, 3,
                         [out, out_plane](int64_t h) { return PlanesOut<F, true>{out + h, out_plane}; },
                         PlanesOut<F, false>{out, out_plane}, f);
        return;
    }
    pair_packet_loop<kAnyLayout, kAnyLayout>(
        m, wo, wi, n, nthreads, bad,
        store_out([out, out_plane](int64_t i, int64_t cnt, const Spectrum<Packet<F>> &v) {
            if (out_plane == 0) {
                store3_lanes(out, i, cnt, v);
            } else {
                for (int c = 0; c < 3; ++c) store1_lanes(out + c * out_plane, i, cnt, v[c]);
            }
        }),
        f);
}
template <typename Model, typename F>
void pdf_batch_dirs(const Model &m, const Dirs<F> &wo, const Dirs<F> &wi, int64_t n, TransportMode mode, uint8_t sf,
                    F *out, int nthreads, BadCounts &bad) {
    static_assert(is_vectorized<Model>::value, "pdf_batch_dirs: a packet model (Vectorized = true)");
    const auto pdf = [mode, sf](const auto &mm, const auto &o, const auto &w, int64_t, int64_t) {
        return bsdf_pdf(mm, o, w, mode, sf);
    };
    if (wo.layout == DirLayout::Planes && wi.layout == DirLayout::Planes) {
        planes_pair_loop(m, wo, wi, n, nthreads, bad, out, 1,
                         [out](int64_t h) { return RowsOut<F, 1, true, true>{out + h}; }, RowsOut<F, 1, false>{out}, pdf);
        return;
    }
    pair_packet_loop<kAnyLayout, kAnyLayout>(
        m, wo, wi, n, nthreads, bad,
        store_out([out](int64_t i, int64_t cnt, const Packet<F> &v) { store1_lanes(out, i, cnt, v); }), pdf);
}

// Rows of C (an (N, C) C-order array at dst) from C component planes n elements apart at src (an
// (N, C) Fortran-order array), over the pool's threads: the layout the kernels without a planes
// path read (sample's wo and u), made by packets (planes loaded, rows stored as store_lanes
// does), each output line written by the thread that owns its chunk. False if an interrupt
// stopped it (dst then incomplete), as parallel_chunks.
template <int C, typename F> bool planes_to_rows(const F *src, int64_t n, F *dst, int nthreads) {
    return parallel_chunks(n, nthreads, kChunk, [&](int64_t b, int64_t e) {
        for (int64_t i = b; i < e; i += kW<F>) {
            const int64_t cnt = std::min(kW<F>, e - i);
            Packet<F> v[C];
            for (int c = 0; c < C; ++c) v[c] = load1_lanes(src + c * n, i, cnt, F(0));
            store_lanes<C>(dst, i, cnt, v);
        }
    });
}

template <typename F> struct SampleOut {
    F *wi, *f, *pdf, *eta;
    uint8_t *flags;
    bool *valid, *proportional;
};

// Models whose sample_f branches on a loop-invariant smoothness test (Conductor, Dielectric)
// expose is_smooth(), sample_smooth and sample_rough (core/bxdf.h); sample_batch then runs one
// branch-free loop per case.

// The same results as bsdf_sample per element, over one chunk [b, e). The main loop stores only
// float outputs (an invalid sample has pdf = 0; validity is folded into float selects) and
// stages flags and pdf_is_proportional as F, so it vectorizes; a second pass writes the
// byte-wide outputs (valid = pdf > 0, exactly bsdf_sample's rule). The pointers are restrict:
// the outputs overlap neither each other nor the inputs (bind_model.h checks); without it the
// loop needs more run-time alias checks than GCC emits (--param vect-max-version-for-alias-checks).
template <int SO, typename Model, typename F, typename Sampler>
inline void sample_chunk(const Model &m, const Sampler &smp, bool model_ok, int64_t b, int64_t e,
                         const F *__restrict wo, const F *__restrict uc, const F *__restrict u, F *__restrict owi,
                         F *__restrict of, F *__restrict opdf, F *__restrict oeta, F *__restrict stage,
                         uint8_t *__restrict ofl, bool *__restrict ovalid, bool *__restrict oprop, int64_t *bo_out) {
    int64_t bo = 0;
    for (int64_t i = b; i < e; ++i) {
        Vec3<F> o = load3<F, SO>(wo, i);
        bo += check_dir(&o);
        // Uniforms on [0, 1) (OneMinusEpsilon), as in bsdf_sample.
        BSDFSample<F> s = smp(m, o, clamp_uniform(uc[i]), clamp_uniform(Point2<F>{u[2 * i], u[2 * i + 1]}));
        bool ok = sample_accepted(s, o) & model_ok;   // bsdf_sample's rule (core/bsdf.h)
        for (int c = 0; c < 3; ++c) of[3 * i + c] = ok ? s.f[c] : F(0);
        owi[3 * i] = ok ? s.wi.x : F(0);      // an invalid sample carries the normal (0, 0, 1)
        owi[3 * i + 1] = ok ? s.wi.y : F(0);  // (kInvalidSampleWi, core/bsdf.h)
        owi[3 * i + 2] = ok ? s.wi.z : F(1);
        opdf[i] = ok ? s.pdf : F(0);
        oeta[i] = ok ? s.eta : F(1);
        F tag = F(s.flags) + (s.pdf_is_proportional ? F(256) : F(0)); // flags + 256 * proportional
        stage[i - b] = ok ? tag : F(0);
    }
    for (int64_t i = b; i < e; ++i) {
        int32_t t = int32_t(stage[i - b]);
        ofl[i] = uint8_t(t & 255);
        oprop[i] = (t >> 8) != 0;
        ovalid[i] = opdf[i] > F(0);
    }
    *bo_out = bo;
}

// Lanes of a packet holding small non-negative integers (flags, 0/1) as bytes [i, i + cnt).
// A full packet converts in registers (GCC's vector conversions: vcvttps2dq + vpmovdb on
// AVX-512); a lane-by-lane loop there became scalar conversions.
template <typename F> inline void store_bytes(uint8_t *p, int64_t i, int64_t cnt, const Packet<F> &v) {
#if defined(__GNUC__) && !defined(__clang__)
    if (cnt == kW<F>) {
        typedef F vf __attribute__((vector_size(sizeof(F) * kPacketWidth)));
        typedef int32_t vi __attribute__((vector_size(4 * kPacketWidth)));
        typedef uint8_t vb __attribute__((vector_size(kPacketWidth)));
        static_assert(sizeof(vf) == sizeof(Packet<F>), "store_bytes: packet layout");
        vf x;
        std::memcpy(&x, &v, sizeof(vf));
        vi ints = __builtin_convertvector(x, vi);
#if defined(__AVX512BW__)
        vb bytes = __builtin_convertvector(ints, vb); // vpmovdb
#else
        // the low byte of each int32 lane (the values are < 256): one byte shuffle, where
        // GCC's narrowing conversion extracts lane by lane without vpmovdb
        typedef uint8_t vq __attribute__((vector_size(4 * kPacketWidth)));
        static_assert(kPacketWidth == 16, "store_bytes: the byte shuffle below is for 16 lanes");
        vq raw;
        std::memcpy(&raw, &ints, sizeof(vq));
        vb bytes = __builtin_shufflevector(raw, raw, 0, 4, 8, 12, 16, 20, 24, 28, 32, 36, 40, 44, 48, 52, 56, 60);
#endif
        std::memcpy(p + i, &bytes, sizeof(vb));
        return;
    }
#endif
    alignas(64) F t[kW<F>];
    drjit::store_aligned(t, v);
    for (int64_t j = 0; j < cnt; ++j) p[i + j] = uint8_t(int32_t(t[j]));
}
// A packet mask as bytes 0 / 1 [i, i + cnt) (the bool outputs). A full float32 packet with
// AVX-512BW / VL: one byte move from the mask register (vmovdqu8 with zeroing), where the float
// path blends and converts twice (vcvttps2dq, vpmovdb); other packets through store_bytes.
template <typename F> inline void store_mask_bytes(uint8_t *p, int64_t i, int64_t cnt, const Mask<Packet<F>> &m) {
#if defined(__AVX512BW__) && defined(__AVX512VL__)
    static_assert(kPacketWidth == 16, "store_mask_bytes: one 16-bit mask per packet");
    // float32 only: float64's two 8-lane mask halves joined so ran 0.97-1.00x (session 26)
    if constexpr (sizeof(F) == 4) {
        if (cnt == kW<F>) {
            _mm_storeu_si128(reinterpret_cast<__m128i *>(p + i), _mm_maskz_mov_epi8(m.k, _mm_set1_epi8(1)));
            return;
        }
    }
#endif
    store_bytes(p, i, cnt, mask_to_float<Packet<F>>(m));
}
// Lanes outside [0, 1] or NaN (a NaN fails both comparisons); count_bad_uniforms per packet
// (padding lanes hold 0).
template <typename F> inline int64_t count_bad_lanes(const Packet<F> &v) {
    return count_failed((v >= F(0)) & (v <= F(1)));
}

// The sample kernels' uniforms of lanes [i, i + cnt) (uc, and u's pairs; padding 0), their
// lanes outside [0, 1] or NaN added to *buc / *bu.
template <typename F>
inline void load_uniforms(const F *uc, const F *u, int64_t i, int64_t cnt, Packet<F> *c, Packet<F> (&uv)[2],
                          int64_t *buc, int64_t *bu) {
    static constexpr F pad_u[2] = {F(0), F(0)};
    load_lanes<2, 2>(u, i, cnt, pad_u, uv);
    *c = load1_lanes(uc, i, cnt, F(0));
    *buc += count_bad_lanes(*c);
    if (cnt == kW<F>) {
        // u's 2 kW scalars as they lie in memory, not the transposed pairs: the same count, and a
        // sampler that ignores u (the smooth lobes) leaves the transposition dead.
        using P = Packet<F>;
        *bu += count_bad_lanes(drjit::load<P>(u + 2 * i)) + count_bad_lanes(drjit::load<P>(u + 2 * i + kW<F>));
    } else {
        *bu += count_bad_lanes(uv[0]) + count_bad_lanes(uv[1]);
    }
}

// sample_chunk on the packet path: the same outputs and rules, kPacketWidth lanes at a time, in
// one pass: the uniforms are checked on the loaded packets and the byte outputs (flags, valid,
// pdf_is_proportional) written from registers (the scalar path's staging pass is not needed).
// Returns the bad (wo, uc, u) counts. Full: e - b is a multiple of kPacketWidth, so every packet's
// loads and stores take their full-packet form, with no lane-count branch per load and store
// (sample_chunks runs a chunk's whole packets so and its last, partial one in a call of its own).
template <int SO, bool Stream, bool Full = false, typename Model, typename F, typename Sampler>
inline void sample_chunk_packet(const Model &m, const Sampler &smp, bool model_ok, int64_t b, int64_t e,
                                const F *__restrict wo, const F *__restrict uc, const F *__restrict u,
                                F *__restrict owi, F *__restrict of, F *__restrict opdf, F *__restrict oeta,
                                uint8_t *__restrict ofl, bool *__restrict ovalid, bool *__restrict oprop,
                                bool prefetch, int64_t (&bad_out)[3]) {
    using P = Packet<F>;
    int64_t bo = 0, buc = 0, bu = 0;
    const Mask<P> model_mask(model_ok);
    // A local copy of the sampler closure (as pair_packet_loop's): the mode and sample flags it
    // captures then cannot alias the byte outputs, so they are not reloaded (nor their masks
    // rebuilt) after every packet's byte stores.
    const Sampler sp = smp;
    const int64_t pf_end = prefetch ? e : b;  // as pair_packet_loop
    // The float outputs through RowsOut (Stream: those on whole lines streamed); the bytes plain.
    const auto w_wi = RowsOut<F, 3, Stream>{owi}.writer(), w_f = RowsOut<F, 3, Stream>{of}.writer();
    const auto w_pdf = RowsOut<F, 1, Stream>{opdf}.writer(), w_eta = RowsOut<F, 1, Stream>{oeta}.writer();
    for (int64_t i = b; i < e; i += kW<F>) {
        const int64_t cnt = Full ? kW<F> : std::min(kW<F>, e - i);
        if (i + kPrefetchAhead + kW<F> <= pf_end) {
            const int64_t j = i + kPrefetchAhead;
            prefetch_dirs<SO>(dirs_of<SO>(wo), j);
            prefetch_span(uc + j, sizeof(F) * size_t(kW<F>));
            prefetch_span(u + 2 * j, 2 * sizeof(F) * size_t(kW<F>));
        }
        Vec3<P> o = load3_lanes<SO>(wo, i, cnt);
        bo += count_not_unit(o);
        P c, uv[2];
        load_uniforms(uc, u, i, cnt, &c, uv, &buc, &bu);
        // Uniforms on [0, 1) (OneMinusEpsilon), as in bsdf_sample.
        BSDFSample<P> s = sp(m, o, clamp_uniform(c), clamp_uniform(Point2<P>{uv[0], uv[1]}));
        Mask<P> ok = sample_accepted(s, o) & model_mask; // bsdf_sample's rule (core/bsdf.h)
        P pdf = select(ok, s.pdf, P(0));
        w_f.put(i, cnt, select(ok, s.f, Spectrum<P>(P(0))));
        w_wi.put(i, cnt, select(ok, s.wi, kInvalidSampleWi<P>()));
        w_pdf.put(i, cnt, pdf);
        w_eta.put(i, cnt, select(ok, s.eta, P(1)));
        store_bytes(ofl, i, cnt, select(ok, s.flags, P(0)));
        store_mask_bytes<F>(reinterpret_cast<uint8_t *>(oprop), i, cnt, ok & s.pdf_is_proportional);
        store_mask_bytes<F>(reinterpret_cast<uint8_t *>(ovalid), i, cnt, pdf > F(0));
    }
    stream_fence<Stream>();
    bad_out[0] = SO == 0 ? (bo > 0 ? e - b : 0) : bo;
    bad_out[1] = buc;
    bad_out[2] = bu;
}

// sample_batch's loop over chunks, the packet path streaming its outputs or not (Stream): one
// instantiation per parallel_chunks call, as both loops inlined in one chunk function cost the
// plain one 3-8 % in cache (session 21).
// A chunk's whole packets run in a loop whose lane count is the constant kPacketWidth, its last,
// partial packet (the array's padded tail) out of line through the same model code: in the loop
// with a run-time count every load and store kept its tail branch and GCC spilled around them.
// Zen 4, tools/perf/loop_ab.py harness, 1 thread, medians of 5 alternating runs (session 24): float32
// in cache 1.01-1.13x (Diffuse 1.12x, DiffuseTransmission 1.13x, NormalizedFresnel 1.07x, rough
// Dielectric 0.99x), N = 1e6 1.00-1.17x; float64 in cache 0.96-1.15x (smooth Dielectric 0.96x,
// Diffuse / Hair 1.15x); an AVX2 build (x86-64-v3) 0.97-1.06x. Bit-identical: the same packets.
// (The eval / pdf loop split so ran 0.77-1.17x by model: not done.)
template <int SO, bool Stream, typename Model, typename F, typename Sampler>
void sample_chunks(const Model &m, const Sampler &sampler, const F *wo, const F *uc, const F *u, int64_t n,
                   bool model_ok, const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    parallel_chunks(n, nthreads, kChunk, [&, model_ok](int64_t b, int64_t e) __attribute__((flatten)) {
        const DenormalsFlushedFor<Model> ftz;
        LocalModel<Model> mloc = m;
        if constexpr (is_vectorized<Model>::value) {
            int64_t c[3] = {0, 0, 0}, t[3] = {0, 0, 0};
            const int64_t e_full = b + (e - b) / kW<F> * kW<F>;
            sample_chunk_packet<SO, Stream, true>(mloc, sampler, model_ok, b, e_full, wo, uc, u, out.wi, out.f, out.pdf,
                                                  out.eta, out.flags, out.valid, out.proportional, n >= kPrefetchMinN, c);
            if (e_full < e)  // out of line (by value, but t), so the loop above keeps its registers
                [=, &t]() __attribute__((noinline)) {
                    sample_chunk_packet<SO, false>(mloc, sampler, model_ok, e_full, e, wo, uc, u, out.wi, out.f,
                                                   out.pdf, out.eta, out.flags, out.valid, out.proportional, false, t);
                }();
            bad.wo += c[0] + t[0];
            bad.uc += c[1] + t[1];
            bad.u += c[2] + t[2];
        } else {
            F stage[kChunk];
            int64_t bo = 0, buc = count_bad_uniforms(uc, b, e), bu = count_bad_uniforms(u, 2 * b, 2 * e);
            sample_chunk<SO>(mloc, sampler, model_ok, b, e, wo, uc, u, out.wi, out.f, out.pdf, out.eta, stage,
                             out.flags, out.valid, out.proportional, &bo);
            bad.wo += bo;
            bad.uc += buc;
            bad.u += bu;
        }
    });
}

template <int SO, typename Model, typename F, typename Sampler>
void sample_batch_loop(const Model &m, const Sampler &sampler, const F *wo, const F *uc, const F *u, int64_t n,
                       uint8_t sf, const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    const bool model_ok = (m.flags() & sf) != 0;
    if constexpr (is_vectorized<Model>::value && SO == 3 && kStreamSamples<F> && streams_samples<Model>::value) {
        // wo, uc, u in; wi, f, pdf, eta and three bytes out; streamed where a float output starts
        // on a line (RowsOut checks each).
        if (big_enough_to_stream(n * (int64_t(sizeof(F)) * (3 + 3 + 8) + 3)) && instance_streams(m) &&
            (on_line(out.wi) || on_line(out.f) || on_line(out.pdf) || on_line(out.eta))) {
            sample_chunks<SO, true>(m, sampler, wo, uc, u, n, model_ok, out, nthreads, bad);
            return;
        }
    }
    sample_chunks<SO, false>(m, sampler, wo, uc, u, n, model_ok, out, nthreads, bad);
}

template <int SO, typename Model, typename F>
void sample_batch(const Model &m, const F *wo, const F *uc, const F *u, int64_t n, TransportMode mode, uint8_t sf,
                  const SampleOut<F> &out, int nthreads, BadCounts &bad) {
    if constexpr (has_split_sample<Model>::value) {
        // Generic on the evaluation type (F, or Packet<F> on the packet path).
        auto smooth = [mode, sf](const auto &mm, const auto &o, auto c, auto) {
            return mm.sample_smooth(o, c, mode, sf);
        };
        auto rough = [mode, sf](const auto &mm, const auto &o, auto c, auto p) {
            return mm.sample_rough(o, c, p, mode, sf);
        };
        if (m.is_smooth()) sample_batch_loop<SO>(m, smooth, wo, uc, u, n, sf, out, nthreads, bad);
        else sample_batch_loop<SO>(m, rough, wo, uc, u, n, sf, out, nthreads, bad);
    } else {
        auto any = [mode, sf](const auto &mm, const auto &o, auto c, auto p) {
            return mm.sample_f(o, c, p, mode, sf);
        };
        sample_batch_loop<SO>(m, any, wo, uc, u, n, sf, out, nthreads, bad);
    }
}

// Directional albedo rho(wo) = E[f |cos wi| / pdf] (pbrt-v4 BxDF::rho), skipping pdf = 0
// samples (pbrt-v4 #313). Uniforms come from a counter hash of (seed, wo index, sample index),
// summed in fixed blocks and then in block order: deterministic for any thread count.
// model_of(j): the model of direction j (the uniform call's one model, or per-element parameters'
// model, batch_varying.h).
template <typename ModelOf, typename F>
void albedo_batch_of(const ModelOf &model_of, const F *wo, int64_t n_wo, int64_t n_samples, uint64_t seed,
                     TransportMode mode, F *out, int nthreads, BadCounts &bad) {
    using Model = std::decay_t<decltype(model_of(int64_t(0)))>;
    const int64_t block = 4096;
    int64_t nblocks = (n_samples + block - 1) / block;
    std::vector<double> partial(size_t(n_wo * nblocks * 3), 0.0);
    parallel_chunks(n_wo * nblocks, nthreads, 1, [&](int64_t item, int64_t) {
        int64_t j = item / nblocks, blk = item % nblocks;
        const Model &m = model_of(j);  // built outside the model's FTZ scope, as the uniform model is
        const DenormalsFlushedFor<Model> ftz;
        Vec3<F> o = load3<F, 3>(wo, j);
        int64_t bad_o = check_dir(&o);
        if (blk == 0) bad.wo += bad_o;
        int64_t s0 = blk * block, s1 = std::min(n_samples, s0 + block);
        double acc[3] = {0, 0, 0};
        for (int64_t k = s0; k < s1; ++k) {
            uint64_t h = hash3(seed, uint64_t(j), uint64_t(k));
            F uc = uniform_from_bits<F>(mix64(h ^ 1)), u0 = uniform_from_bits<F>(mix64(h ^ 2)),
              u1 = uniform_from_bits<F>(mix64(h ^ 3));
            BSDFSample<F> s = bsdf_sample(m, o, uc, Point2<F>{u0, u1}, mode, uint8_t(RT_All));
            F w = s.valid ? AbsCosTheta(s.wi) / s.pdf : F(0);
            for (int c = 0; c < 3; ++c) acc[c] += double(s.f[c] * w);
        }
        for (int c = 0; c < 3; ++c) partial[size_t(item * 3 + c)] = acc[c];
    });
    for (int64_t j = 0; j < n_wo; ++j)
        for (int c = 0; c < 3; ++c) {
            double sum = 0;
            for (int64_t blk = 0; blk < nblocks; ++blk) sum += partial[size_t((j * nblocks + blk) * 3 + c)];
            out[3 * j + c] = n_samples > 0 ? F(sum / double(n_samples)) : F(0);
        }
}

template <typename Model, typename F>
void albedo_batch(const Model &m, const F *wo, int64_t n_wo, int64_t n_samples, uint64_t seed, TransportMode mode,
                  F *out, int nthreads, BadCounts &bad) {
    albedo_batch_of([&m](int64_t) -> const Model & { return m; }, wo, n_wo, n_samples, seed, mode, out, nthreads, bad);
}

} // namespace bsdfkit
