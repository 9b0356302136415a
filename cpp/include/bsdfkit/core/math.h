// Scalar math vocabulary shared by every model.
//
// The rules that keep the batch loops (batch.h) vectorized, stated once; model code follows them
// without repeating why (GCC 12/13 auto-vectorizer, -O3 -fno-math-errno -fno-trapping-math):
//  V1 Masks are bools combined with bitwise & and |, accumulated Mitsuba-style (`active &= ...`)
//     and applied once at the end: && / || become branches, and early returns end vectorization.
//  V2 Select floats, not bools: fold a lobe's validity into its float (pdf = 0) or write a flag
//     by arithmetic (lobe_flag, core/bsdf_sample.h); a bool-valued select (reflect ? ok_r : ok_t)
//     and a byte select do not vectorize, nor do the bool COND_EXPRs if-conversion makes of &&.
//  V3 A loop-invariant test (sample_flags, a model switch) masks a value by its bits
//     (keep_or_zero; restrict_lobes): a select on an invariant bool does not vectorize in float64.
//     Model switches are stored as F (0 or 1), not bool, so they can mask a float vector.
//  V4 max_/min_/clamp are selects (no fmin/fmax: their NaN rules block it; on packets the same
//     lanes by x86's MAXPS / MINPS, core/simd.h minmax_lanes); no errno-setting calls; sin and
//     cos through sincos_ (libm's have no vector form without -ffast-math).
//  V5 Avoid selects whose operands are themselves selected divisions (two safe_divs in a row) and
//     tests repeated between a model and the BSDF-level rules: GCC's PRE merges them into bool
//     selects. -ffp-contract=off keeps vector body and scalar remainder bit-identical.
// Check with the CMake option BSDFKIT_VEC_REPORT=ON (-fopt-info-vec-optimized).
// These rules serve the models on the scalar, auto-vectorized loops. Models with `Vectorized = true`
// (Diffuse, Conductor, Dielectric) run on explicit packets instead (core/simd.h, batch.h), where
// the same mask idiom holds but the compiler's vectorizer is not involved.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "simd.h"

namespace bsdfkit {

// Math calls in model code are unqualified (sqrt(x)): std:: for scalars, and argument-dependent
// lookup finds the packet (drjit::) or dual-number (core/dual.h) overloads for other evaluation types.
using std::abs;
using std::acos;
using std::asin;
using std::atan2;
using std::copysign;
using std::cos;
using std::erf;
using std::exp;
using std::floor;
using std::fma;
using std::log;
using std::pow;
using std::sin;
using std::sqrt;

// The type a model's Params hold and its make() computes derived parameters in: double for float,
// double and packet models; the Dual itself for a Dual model (core/dual.h), so derivatives flow
// through the preprocessing. (scalar_t<V>, core/simd.h, is the scalar under V; a Dual's value type.)
template <typename F> struct ParamOf { using type = double; };
template <typename F> using param_t = typename ParamOf<F>::type;
// The type a colour field of Params holds for a model whose channel values are C: param_t<F>
// when C is F; Packet<double> when C is a packet (a value per lane: the generic spectral form,
// batch_spectral.h ColourSpectral, evaluates the colours at each lane's wavelengths in double).
template <typename F, typename C>
using colour_param_t = std::conditional_t<is_packet_v<C>, Packet<double>, param_t<F>>;
// x without derivatives, and whether x carries any (plain numbers: itself, false; core/dual.h).
template <typename T> constexpr T value_of(T x) { return x; }
template <typename T> constexpr bool is_variable(T) { return false; }

// t[x] per lane for an integer-valued float index x (caller keeps x in range): a gather for
// packets, a load for scalars (and Dual evaluation types, through value_of).
template <typename T, typename V> inline V gather_index(const T *t, const V &x) {
    if constexpr (is_packet_v<V>) return drjit::gather<V>(t, drjit::int32_array_t<V>(x));
    else return V(t[int(value_of(x))]);
}

template <typename Float> inline constexpr Float Pi = Float(3.14159265358979323846);
template <typename Float> inline constexpr Float InvPi = Float(0.31830988618379067154);
template <typename Float> inline constexpr Float Inv2Pi = Float(0.15915494309189533577);
template <typename Float> inline constexpr Float InvSqrtPi = Float(0.56418958354775628695);
template <typename Float> inline constexpr Float PiOver2 = Float(1.57079632679489661923);
template <typename Float> inline constexpr Float PiOver4 = Float(0.78539816339744830962);

// (sqr, safe_sqrt, clamp and lerp have Dr.Jit namesakes; core/simd.h overloads them for packets.)
template <typename T> inline T sqr(T x) { return x * x; }
// a * b + c rounded once where the CPU has FMA (one instruction), else a * b + c: the same arithmetic
// for scalars, packets (drjit::fmadd) and dual numbers (core/dual.h), so every instantiation of a
// model keeps the same bits (the build forbids the compiler's own contraction, CMakeLists.txt).
template <typename T> inline T mul_add(const T &a, const T &b, const T &c) {
#if defined(__FMA__)
    if constexpr (std::is_arithmetic_v<T>) return std::fma(a, b, c);
    else return fmadd(a, b, c);
#else
    return a * b + c;
#endif
}
// c - a * b and a * b - c, rounded once: mul_add(-a, b, c) and mul_add(a, b, -c) bit for bit. On
// packets one instruction each (vfnmadd / vfmsub): GCC does not fold a packet's sign flip (an xor
// with the sign mask) into the FMA after it.
template <typename T> inline T neg_mul_add(const T &a, const T &b, const T &c) {
#if defined(__FMA__)
    if constexpr (is_packet_v<T>) return fnmadd(a, b, c);
#endif
    return mul_add(T(-a), b, c);
}
template <typename T> inline T mul_sub(const T &a, const T &b, const T &c) {
#if defined(__FMA__)
    if constexpr (is_packet_v<T>) return fmsub(a, b, c);
#endif
    return mul_add(a, b, T(-c));
}
// max/min as selects: operands are finite in every use, and selects vectorize.
// On packets one MAXPS / MINPS each (minmax_lanes, core/simd.h: the same lanes).
template <typename T> inline T max_(T a, T b) {
    if constexpr (is_packet_v<T>) return minmax_lanes<true>(a, b);
    else return select(a > b, a, b);
}
template <typename T> inline T min_(T a, T b) {
    if constexpr (is_packet_v<T>) return minmax_lanes<false>(a, b);
    else return select(a < b, a, b);
}
template <typename T> inline T clamp(T x, T lo, T hi) { return select(x < lo, lo, select(x > hi, hi, x)); }
template <typename T> inline T lerp(T t, T a, T b) { return (1 - t) * a + t * b; }
template <typename T> inline T safe_sqrt(T x) { return sqrt(select(x > T(0), x, T(0))); }
template <typename T> inline T safe_div(T a, T b) { return select(b != T(0), a / b, T(0)); }
template <typename T> inline T copysign1(T mag, T sgn) { return select(sgn < T(0), -mag, mag); }
// v with its sign flipped where s < 0: on packets an exclusive or with s's sign bit (Dr.Jit's
// mulsign; no multiplier), which flips at s = -0 as well, where the scalar form does not; callers
// use it where s = +-0 is masked out.
template <typename T> inline T mulsign_(T v, T s) {
    if constexpr (is_packet_v<T>) return drjit::mulsign(v, s);
    else return select(s < T(0), -v, v);
}

// t[x] and d[x] per lane for two 64-entry tables (a table and its slopes) and one integer-valued
// float index x. For a 16-lane float packet on AVX-512 each table sits in four registers and each
// half is read by one two-register permutation (vpermi2ps; GCC's vector extensions, as batch.h's
// shuffles, so GCC only), bit 5 of the index picking the half, the index conversion and the half
// choice shared by both tables: no gather. Any index reads some entry there (its low 6 bits); the
// gather path (gather_index) clamps x to [0, 63], so lanes a caller masks out (NaN, x < 0) never
// read outside the tables. Both give t[x], d[x] for x in [0, 63].
template <typename T, typename V>
inline void lookup64x2(const T *t, const T *d, const V &x, V *a, V *b) {
#if defined(__AVX512F__) && defined(__GNUC__) && !defined(__clang__)
    if constexpr (is_packet_v<V> && std::is_same_v<T, float> && std::is_same_v<scalar_t<V>, float> &&
                  drjit::size_v<V> == 16) {
        typedef float v16sf __attribute__((vector_size(64)));
        typedef int32_t v16si __attribute__((vector_size(64)));
        drjit::int32_array_t<V> ii(x);
        v16si i;
        std::memcpy(&i, &ii, 64);
        const v16si upper = (i & 32) != 0;
        auto read = [&](const T *tab, V *out) {
            v16sf t0, t1, t2, t3;
            std::memcpy(&t0, tab, 64);
            std::memcpy(&t1, tab + 16, 64);
            std::memcpy(&t2, tab + 32, 64);
            std::memcpy(&t3, tab + 48, 64);
            v16sf r = upper ? __builtin_shuffle(t2, t3, i) : __builtin_shuffle(t0, t1, i);
            std::memcpy(out, &r, 64);
        };
        read(t, a);
        read(d, b);
        return;
    }
    // float64: 64 entries are 8 registers; 4 two-source permutations (vpermt2pd, the
    // index's low 4 bits) and 3 selects on bits 4 and 5 per 8-lane half, instead of hardware
    // gathers. Measured in cache, 1 thread: on a Sapphire Rapids host the float64 rough Plastic
    // pdf +10 % (one lookup per element), its eval (two lookups) -3 to -4 % (the permutations
    // crowding the shuffle port while gathers run on the load ports); on an AMD Zen 4 host (its
    // gathers ~1.3 cycles per element) the eval +18 % and the rough sampler +3 %: permutations.
    if constexpr (is_packet_v<V> && std::is_same_v<T, double> && std::is_same_v<scalar_t<V>, double> &&
                  drjit::size_v<V> % 8 == 0) {
        typedef double v8df __attribute__((vector_size(64)));
        typedef long long v8di __attribute__((vector_size(64)));
        constexpr size_t H = drjit::size_v<V> / 8;
        v8df xv[H];
        std::memcpy(xv, &x, sizeof(xv));
        auto read = [&](const T *tab, V *out) {
            v8df blk[8], r[H];
            std::memcpy(blk, tab, sizeof(blk));
            for (size_t h = 0; h < H; ++h) {
                v8di i = __builtin_convertvector(xv[h], v8di);
                v8di b4 = (i & 16) != 0, b5 = (i & 32) != 0;
                v8df r0 = __builtin_shuffle(blk[0], blk[1], i), r1 = __builtin_shuffle(blk[2], blk[3], i);
                v8df r2 = __builtin_shuffle(blk[4], blk[5], i), r3 = __builtin_shuffle(blk[6], blk[7], i);
                r[h] = b5 ? (b4 ? r3 : r2) : (b4 ? r1 : r0);
            }
            std::memcpy(out, r, sizeof(r));
        };
        read(t, a);
        read(d, b);
        return;
    }
#endif
    V xi = min_(max_(x, V(0)), V(63));
    *a = gather_index(t, xi);
    *b = gather_index(d, xi);
}

// x^y per lane by the scalar libm pow: for packet results that must equal a scalar double
// evaluation bit for bit (the Dual gradient path, core/dual.h, computes std::pow on its value).
template <typename V> inline V pow_libm(const V &x, const V &y) {
    if constexpr (is_packet_v<V>) {
        constexpr size_t W = drjit::size_v<V>;
        alignas(64) scalar_t<V> a[W], b[W];
        drjit::store_aligned(a, x);
        drjit::store_aligned(b, y);
        for (size_t j = 0; j < W; ++j) a[j] = std::pow(a[j], b[j]);
        return drjit::load_aligned<V>(a);
    } else {
        return pow(x, y);
    }
}

// e^x for results that a float64 evaluation must give bit for bit like the scalar double (and Dual)
// path: float64 packets call libm per lane; float packets use Dr.Jit's vector exp (about 1 ulp).
template <typename V> inline V exp_f64libm(const V &x) {
    if constexpr (is_packet_v<V> && std::is_same_v<scalar_t<V>, double>) {
        constexpr size_t W = drjit::size_v<V>;
        alignas(64) double a[W];
        drjit::store_aligned(a, x);
        for (size_t j = 0; j < W; ++j) a[j] = std::exp(a[j]);
        return drjit::load_aligned<V>(a);
    } else {
        return exp(x);
    }
}

// sin and cos of x together, written to vectorize (libm's sin/cos have no vector variant
// without -ffast-math). Cody-Waite reduction by pi/2 with a 3-part constant, then Cephes-style
// minimax polynomials on [-pi/4, pi/4] (Cody & Waite 1980; Moshier, Cephes sinf.c / sin.c).
// About 1 ulp in float and 1e-15 relative in double for |x| <= ~1e4 (samplers use [-pi, 2 pi]).
// Quadrant logic uses float compares and selects only, so it also vectorizes for double.
template <typename F> struct SinCosConst;
template <> struct SinCosConst<float> {
    static constexpr float C1 = 1.5703125f, C2 = 4.837512969970703125e-4f, C3 = 7.54978995489188216e-8f;
};
template <> struct SinCosConst<double> {
    static constexpr double C1 = 1.57079625129699707031e+00, C2 = 7.54978941586159635336e-08,
                            C3 = 5.39030285815811905290e-15;
};
template <typename F> inline void sincos_poly(F r, F *s, F *c) {
    F z = r * r;
    if constexpr (sizeof(scalar_t<F>) == 4) {
        *s = r + r * z * ((F(-1.9515295891e-4) * z + F(8.3321608736e-3)) * z + F(-1.6666654611e-1));
        *c = F(1) - F(0.5) * z +
             z * z * ((F(2.443315711809948e-5) * z + F(-1.388731625493765e-3)) * z + F(4.166664568298827e-2));
    } else {
        F ps = ((((F(1.58962301576546568060e-10) * z + F(-2.50507477628578072866e-8)) * z +
                  F(2.75573136213857245213e-6)) * z + F(-1.98412698295895385996e-4)) * z +
                F(8.33333333332211858878e-3)) * z + F(-1.66666666666666307295e-1);
        F pc = ((((F(-1.13585365213876817300e-11) * z + F(2.08757008419747316778e-9)) * z +
                  F(-2.75573141792967388112e-7)) * z + F(2.48015872888517045348e-5)) * z +
                F(-1.38888888888730564116e-3)) * z + F(4.16666666666665929218e-2);
        *s = r + r * z * ps;
        *c = F(1) - F(0.5) * z + z * z * pc;
    }
}
template <typename F> inline void sincos_(F x, F *sin_out, F *cos_out) {
    using K = SinCosConst<scalar_t<F>>;
    F k = floor(x * F(0.63661977236758134308) + F(0.5)); // nearest multiple of pi/2
    F r = ((x - k * F(K::C1)) - k * F(K::C2)) - k * F(K::C3);
    F q = k - F(4) * floor(k * F(0.25)); // quadrant 0..3, exact
    F s, c;
    sincos_poly(r, &s, &c);
    Mask<F> swap = (q == F(1)) | (q == F(3));
    F s0 = select(swap, c, s), c0 = select(swap, s, c);
    *sin_out = select(q >= F(2), -s0, s0);
    *cos_out = select((q == F(1)) | (q == F(2)), -c0, c0);
}

// x if keep, else +0, by masking the bits: bit-exact (a NaN x stays NaN when kept). For a
// loop-invariant keep, where GCC 12 cannot vectorize a select on an invariant bool.
template <typename F> inline F keep_or_zero(F x, bool keep) {
    if constexpr (!std::is_floating_point_v<F>) {
        return keep ? x : F(0); // packets (and other evaluation types): a uniform branch
    } else {
    using U = std::conditional_t<sizeof(F) == 4, uint32_t, uint64_t>;
    U b, m = keep ? ~U(0) : U(0);
    std::memcpy(&b, &x, sizeof b);
    b &= m;
    std::memcpy(&x, &b, sizeof b);
    return x;
    }
}

template <typename Float> struct Vec3 {
    Float x, y, z;
    Vec3() = default;
    constexpr Vec3(Float x, Float y, Float z) : x(x), y(y), z(z) {}
    Vec3 operator+(const Vec3 &o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3 operator-(const Vec3 &o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3 operator-() const { return {-x, -y, -z}; }
    Vec3 operator*(Float s) const { return {x * s, y * s, z * s}; }
    Vec3 operator/(Float s) const { Float r = Float(1) / s; return {x * r, y * r, z * r}; }
};
template <typename Float> struct is_lane_struct<Vec3<Float>> : std::true_type {};
template <typename Float> inline Vec3<Float> operator*(Float s, const Vec3<Float> &v) { return v * s; }
template <typename Float> inline Float dot(const Vec3<Float> &a, const Vec3<Float> &b) {
    return mul_add(a.x, b.x, mul_add(a.y, b.y, a.z * b.z));
}
template <typename Float> inline Float absdot(const Vec3<Float> &a, const Vec3<Float> &b) {
    return abs(dot(a, b));
}
template <typename Float> inline Vec3<Float> cross(const Vec3<Float> &a, const Vec3<Float> &b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <typename Float> inline Float length_squared(const Vec3<Float> &v) { return dot(v, v); }
template <typename Float> inline Vec3<Float> normalize(const Vec3<Float> &v) {
    return v / sqrt(dot(v, v));
}
template <typename Float>
inline Vec3<Float> select(const Mask<Float> &c, const Vec3<Float> &a, const Vec3<Float> &b) {
    return {select(c, a.x, b.x), select(c, a.y, b.y), select(c, a.z, b.z)};
}
// Flip v into the hemisphere of n.
template <typename Float> inline Vec3<Float> face_forward(const Vec3<Float> &v, const Vec3<Float> &n) {
    return select(dot(v, n) < Float(0), -v, v);
}

template <typename Float> struct Point2 {
    Float x, y;
};

} // namespace bsdfkit
