// The mask / select vocabulary shared by scalar and packet instantiations of the model code.
//
// Model code is written once on an evaluation type V: a scalar (float, double; Mask<V> = bool)
// or a packet of kPacketWidth lanes (Packet<float> / Packet<double>, Dr.Jit's header-only packet
// arrays from the `drjit` wheel, the types Mitsuba's own kernels are written in; Mask<V> is
// their lane mask). The idiom is Mitsuba's: a per-element condition is a mask, accumulated with
// `active &= ...` and applied once with `select(active, value, 0)`; no ternaries, `&&`/`||` or
// early returns on per-element values. Math calls are unqualified (sqrt(x), abs(x), floor(x);
// core/math.h brings std:: into bsdfkit), so argument-dependent lookup picks drjit:: for
// packets. Divide and sqrt are the exact IEEE ones in both forms (no rcp/rsqrt approximations).
#pragma once
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>
#if defined(__SSE__)
#include <immintrin.h> // _mm_getcsr / _mm_setcsr (DenormalsFlushed)
#endif

#include <drjit/math.h>

#include "../batch_policy.h"  // flushes_denormals<M>: the batch layer's policy table
#include <drjit/packet.h>

namespace bsdfkit {

// Lanes per packet of the batch kernels (measured on Zen 3 / AVX2: 16 lanes = two ymm registers
// per value beat 8 on the rough conductor eval; docs/dev/performance.md, "Keep 16 lanes").
inline constexpr size_t kPacketWidth = 16;

template <typename T> using Packet = drjit::Packet<T, kPacketWidth>;

template <typename T, typename = void> struct simd_traits {
    using Scalar = T;
    using Mask = bool;
    static constexpr size_t Width = 1;
};
template <typename T> struct simd_traits<T, std::enable_if_t<drjit::is_array_v<T>>> {
    using Scalar = drjit::scalar_t<T>;
    using Mask = drjit::mask_t<T>;
    static constexpr size_t Width = drjit::size_v<T>;
};

// Lane mask of V (bool for a scalar), its scalar element type, and its width.
template <typename V> using Mask = typename simd_traits<V>::Mask;
template <typename V> using scalar_t = typename simd_traits<V>::Scalar;
template <typename V> inline constexpr bool is_packet_v = drjit::is_array_v<V>;

// Scalar forms of the mask reductions; packets use drjit::any/all/none by ADL.
inline bool any(bool b) { return b; }
inline bool all(bool b) { return b; }
inline bool none(bool b) { return !b; }

// Structs of per-lane values (Vec3, Spectrum) have their own select overloads.
template <typename T> struct is_lane_struct : std::false_type {};

// select(mask, a, b) for scalars (drjit::select serves packets by ADL).
template <typename T, std::enable_if_t<!is_lane_struct<T>::value, int> = 0>
inline T select(bool c, const T &a, const T &b) { return c ? a : b; }

// A mask as V: 1 where set, else 0.
template <typename V> inline V mask_to_float(const Mask<V> &m) {
    if constexpr (is_packet_v<V>) return drjit::select(m, V(1), V(0));
    else return m ? V(1) : V(0);
}

// Our helpers whose names Dr.Jit also defines (deprecated there, or with another argument
// order: drjit::lerp(a, b, t)), as exact overloads for packets, which argument-dependent lookup
// would otherwise make ambiguous. Same formulas as the scalar ones in core/math.h.
template <typename T, size_t N> using PacketT = drjit::Packet<T, N>;
template <typename T, size_t N> inline PacketT<T, N> sqr(const PacketT<T, N> &x) { return x * x; }
// x86's MAXPS / MINPS lane by lane: a > b ? a : b and a < b ? a : b, i.e. exactly the lanes of
// select(a > b, a, b) / select(a < b, a, b), NaN and signed zeros included (the second operand
// wherever the compare fails), in one instruction where GCC keeps the select as a compare into a
// mask register and a blend. (Dr.Jit's minimum / maximum add a NaN fix-up: two instructions.)
// On a packet's native register (its member m), on both halves of a packet of several (a1, a2),
// else through the select.
namespace detail_minmax {
#if defined(__SSE2__)
template <bool Max> inline __m128 op(__m128 a, __m128 b) { return Max ? _mm_max_ps(a, b) : _mm_min_ps(a, b); }
template <bool Max> inline __m128d op(__m128d a, __m128d b) { return Max ? _mm_max_pd(a, b) : _mm_min_pd(a, b); }
#endif
#if defined(__AVX__)
template <bool Max> inline __m256 op(__m256 a, __m256 b) { return Max ? _mm256_max_ps(a, b) : _mm256_min_ps(a, b); }
template <bool Max> inline __m256d op(__m256d a, __m256d b) {
    return Max ? _mm256_max_pd(a, b) : _mm256_min_pd(a, b);
}
#endif
#if defined(__AVX512F__)
template <bool Max> inline __m512 op(__m512 a, __m512 b) { return Max ? _mm512_max_ps(a, b) : _mm512_min_ps(a, b); }
template <bool Max> inline __m512d op(__m512d a, __m512d b) {
    return Max ? _mm512_max_pd(a, b) : _mm512_min_pd(a, b);
}
#endif
// (the traits take the packet, not its register type: a vector type as a template argument
// draws GCC's -Wignored-attributes)
template <bool Max, typename P, typename = void> struct native : std::false_type {};
template <bool Max, typename P>
struct native<Max, P, std::void_t<decltype((void)op<Max>(std::declval<P &>().m, std::declval<P &>().m))>>
    : std::true_type {};
template <typename P, typename = void> struct halves : std::false_type {};
template <typename P> struct halves<P, std::void_t<decltype((void)std::declval<P &>().a1)>> : std::true_type {};
} // namespace detail_minmax
template <bool Max, typename P> inline P minmax_lanes(const P &a, const P &b) {
    using namespace detail_minmax;
    if constexpr (native<Max, P>::value) {
        P r;
        r.m = op<Max>(a.m, b.m);
        return r;
    } else if constexpr (halves<P>::value) {
        return P(minmax_lanes<Max>(a.a1, b.a1), minmax_lanes<Max>(a.a2, b.a2));
    } else {
        return Max ? drjit::select(a > b, a, b) : drjit::select(a < b, a, b);
    }
}
// select(x < lo, lo, select(x > hi, hi, x)) as max(lo, min(hi, x)) lane by lane: the same lanes
// for lo <= hi (every caller's bounds are ordered constants), NaN kept.
template <typename T, size_t N>
inline PacketT<T, N> clamp(const PacketT<T, N> &x, const PacketT<T, N> &lo, const PacketT<T, N> &hi) {
    return minmax_lanes<true>(lo, minmax_lanes<false>(hi, x));
}
template <typename T, size_t N>
inline PacketT<T, N> lerp(const PacketT<T, N> &t, const PacketT<T, N> &a, const PacketT<T, N> &b) {
    return (T(1) - t) * a + t * b;
}
template <typename T, size_t N> inline PacketT<T, N> safe_sqrt(const PacketT<T, N> &x) {
    return drjit::sqrt(minmax_lanes<true>(x, PacketT<T, N>(T(0)))); // = sqrt(select(x > 0, x, 0))
}

// x where m is set, else +0: the same bits as select(m, x, 0). For packets an AND with the lane
// mask (a compare's all-ones / all-zeros lanes), where GCC makes a blend with zero into an AND
// only after re-deriving the mask from its sign bits (one more instruction per select).
template <typename T, size_t N>
inline PacketT<T, N> zero_unless(const drjit::mask_t<PacketT<T, N>> &m, const PacketT<T, N> &x) {
    return x & m;
}
template <typename T, std::enable_if_t<!drjit::is_array_v<T>, int> = 0> inline T zero_unless(bool m, const T &x) {
    return m ? x : T(0);
}

// Lanes of x in vfpclass's classes Imm (AVX-512DQ: one instruction per register, for float32
// and float64 packets of one or two registers); other packets compute the same lanes by
// `compares(x)`. Imm bits: 0x01 QNaN, 0x02 +0, 0x04 -0, 0x08 +inf, 0x10 -inf, 0x20 denormal,
// 0x40 negative finite, 0x80 SNaN.
template <int Imm, typename P, typename Compares> inline drjit::mask_t<P> in_fp_classes(const P &x, const Compares &compares) {
    using T = drjit::scalar_t<P>;
    constexpr size_t N = drjit::size_v<P>;
#if defined(__AVX512DQ__)
    if constexpr (std::is_same_v<T, float> && N == 16) {
        drjit::mask_t<P> r;
        r.k = _mm512_fpclass_ps_mask(x.m, Imm);
        return r;
    } else if constexpr (std::is_same_v<T, double> && N == 8) {
        drjit::mask_t<P> r;
        r.k = _mm512_fpclass_pd_mask(x.m, Imm);
        return r;
    } else if constexpr (std::is_same_v<T, double> && N == 16) {
        return drjit::mask_t<P>(in_fp_classes<Imm>(x.a1, compares), in_fp_classes<Imm>(x.a2, compares));
    } else
#endif
    {
        return compares(x);
    }
}

// Lanes that fail (x >= 0) & (x <= max): NaN, +-inf and negative non-zero values (-0 passes,
// as it does x >= 0): the classes NaN, +-inf, negative finite (0xD9) instead of two compares
// and a mask AND; the same lanes.
template <typename P, std::enable_if_t<drjit::is_array_v<P>, int> = 0>
inline drjit::mask_t<P> not_finite_nonneg(const P &x) {
    return in_fp_classes<0xD9>(x, [](const auto &v) {
        using T = drjit::scalar_t<std::decay_t<decltype(v)>>;
        return !((v >= T(0)) & (v <= std::numeric_limits<T>::max()));
    });
}

// Lanes that fail (x > 0) & (x <= max): NaN, +-0, +-inf and negative values (a sample's pdf):
// not_finite_nonneg's classes and +0 (0xDF); the same lanes (a positive denormal passes both).
template <typename P, std::enable_if_t<drjit::is_array_v<P>, int> = 0>
inline drjit::mask_t<P> not_finite_positive(const P &x) {
    return in_fp_classes<0xDF>(x, [](const auto &v) {
        using T = drjit::scalar_t<std::decay_t<decltype(v)>>;
        return !((v > T(0)) & (v <= std::numeric_limits<T>::max()));
    });
}

// e^x for a finite x. For float packets with AVX-512: Dr.Jit's exp (the Cephes expf reduction and
// polynomial, about 1 ulp: x = n ln2 + y with n = floor(x / ln2 + 1/2), e^y by its degree-7
// polynomial, then 2^n e^y by vscalef) without its two overflow / underflow selects: for a finite
// x, vscalef already rounds 2^n e^y to +inf past x ~ 88.7 and to 0 (through the denormals) below
// x ~ -103, so only +-inf and NaN arguments, which need them, differ. The same bits as exp(x) for x
// in [-87.3, 88.3]. Without AVX-512 (AVX2, e.g. Zen 3) Dr.Jit's ldexp builds 2^n from exponent
// bits, which wrap for n < -127 (exp(-300) came out as 2e24): there, and for other types, exp(x).
template <typename V> inline V exp_finite(const V &x) {
#if defined(__AVX512F__)
    constexpr bool fast = drjit::is_array_v<V> && std::is_same_v<drjit::scalar_t<V>, float>;
#else
    constexpr bool fast = false;
#endif
    if constexpr (fast) {
        V n = drjit::floor(drjit::fmadd(V(drjit::InvLogTwo<float>), x, V(0.5f)));
        V y = drjit::fmadd(n, V(-0.693359375f), x);  // -ln 2 in two parts (Cephes C1, C2)
        y = drjit::fmadd(n, V(2.12194440e-4f), y);
        V z = drjit::estrin(y, 5.0000001201e-1, 1.6666665459e-1, 4.1665795894e-2, 8.3334519073e-3,
                            1.3981999507e-3, 1.9875691500e-4);
        z = drjit::fmadd(z, drjit::square(y), y + 1.f);
        return drjit::ldexp(z, n);
    } else {
        using std::exp;
        return exp(x);
    }
}

// Models whose line in the batch layer's policy table (batch_policy.h) says flush_denormals run
// their batch kernels (and the preview renderer's shading of them) with the CPU's flush-to-zero and
// denormals-are-zero modes (x86 MXCSR FTZ | DAZ), set per chunk on the thread that runs it and
// restored after: a denormal intermediate then costs nothing instead of a microcode assist (~100+
// cycles each on Intel). Only values below the smallest normal number (1.2e-38 in float) change, to 0.

// Off: nothing to do. The empty constructor makes the guard a non-trivial type, so a guard that is
// only declared (`const DenormalsFlushedFor<M> ftz;`) is not an unused variable to -Wall.
template <bool On> struct DenormalsFlushed {
    DenormalsFlushed() {}
};
#if defined(__SSE__)
template <> struct DenormalsFlushed<true> {
    unsigned saved = _mm_getcsr();
    DenormalsFlushed() { _mm_setcsr(saved | 0x8040u); } // FTZ (bit 15) | DAZ (bit 6)
    ~DenormalsFlushed() { _mm_setcsr(saved); }
    DenormalsFlushed(const DenormalsFlushed &) = delete;
    DenormalsFlushed &operator=(const DenormalsFlushed &) = delete;
};
#endif
template <typename M> using DenormalsFlushedFor = DenormalsFlushed<flushes_denormals<M>::value>;  // batch_policy.h

// Packet load / store of W consecutive scalars (unaligned).
template <typename V> inline V load_packet(const scalar_t<V> *p) { return drjit::load<V>(p); }
template <typename V> inline void store_packet(scalar_t<V> *p, const V &v) { drjit::store(p, v); }

} // namespace bsdfkit
