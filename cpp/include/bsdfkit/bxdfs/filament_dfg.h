// Filament's DFG lookup table, computed by bsdfkit in double precision (no texture is ported).
//
// Layout (ours, not Filament's texture): a size x size x 3 table on a grid that includes the end
// points: row j holds perceptual roughness r_j = j / (size - 1), column i holds
// NoV_i = i / (size - 1) (column 0 is evaluated at NoV = MIN_N_DOT_V = 1e-4, the smallest NoV a
// model looks up; row 0 holds the alpha -> 0 limits x = (1 - NoV)^5, y = 1, z = 0). With
// alpha = r^2 and v = (sqrt(1 - NoV^2), 0, NoV) the three channels are
//   x = integral of D V Fc <NoL> dl,  Fc = (1 - VoH)^5    (multiscatter DFG "x", cmgen DFV_Multiscatter)
//   y = integral of D V <NoL> dl                            (multiscatter DFG "y": GGX albedo with F = 1)
//   z = integral of D_Charlie V_Neubelt <NoL> dl            (cloth DFG, cmgen DFV_Charlie_Uniform)
// with D the GGX NDF, V = V_SmithGGXCorrelated and D_Charlie without the shader's fp16 floor
// on sin^2 (Filament doc "Pre-integration for multiscattering"; libs/ibl CubemapIBL::DFG).
// The runtime reconstruction (1 - f0) x + f0 y is the albedo of the Schlick GGX lobe with f90 = 1.
// Lookups are bilinear. Filament samples a texture at texel centres, which clamps r and NoV
// within half a texel of 0 and 1: at r = 1 that alone leaves the energy-compensated metal 1.4 %
// short of white at size 128, hence the end-point grid.
#pragma once
#include <cstdint>
#include <memory>
#include <type_traits>
#include <vector>

#include "../core/math.h"
#include "../core/table.h"

namespace bsdfkit {

struct FilamentDFG {
    int size = 0;     // texels per axis
    int samples = 0;  // quasi-Monte Carlo samples per texel and channel group
    std::vector<double> d64;  // [(j * size + i) * 3 + c]
    std::vector<float> d32;   // the same values rounded to float

    template <typename F> const F *data() const {
        if constexpr (std::is_same_v<F, float>) return d32.data(); else return d64.data();
    }
};

// The table's content digest (core/table.h): its size, sample count and float64 values.
inline uint64_t content_digest(const FilamentDFG &t) {
    int head[2] = {t.size, t.samples};
    return digest_bytes(t.d64.data(), t.d64.size() * sizeof(double), digest_bytes(head, sizeof head));
}

// Computes rows [row_begin, row_end) of the table into out ((row_end - row_begin) * size * 3
// doubles) on nthreads OpenMP threads; deterministic for any thread count (cpp/src/filament_dfg.cpp).
void filament_dfg_rows(int size, int samples, int row_begin, int row_end, double *out, int nthreads);

// The whole table (no caching here; callers cache, see bsdfkit.filament.dfg_lut).
SharedTable<FilamentDFG> make_filament_dfg(int size, int samples, int nthreads);
// Wraps precomputed values (size * size * 3 doubles in the layout above).
SharedTable<FilamentDFG> make_filament_dfg(int size, int samples, const double *values);

// One roughness row of the table, fixed per model: the row indices and weight are computed once
// at construction, so a per-element lookup only interpolates along NoV.
// F may be a Dual (core/dual.h): the table holds its scalar_t, and the row weight ty carries the
// derivative of the bilinear interpolant along roughness.
template <typename F> struct DFGRow {
    const scalar_t<F> *data = nullptr;
    int size = 0;
    int j0 = 0, j1 = 0;
    F ty = 0;

    DFGRow() = default;
    template <typename S>
    DFGRow(const scalar_t<F> *d, int n, S perceptual_roughness) : data(d), size(n) {
        S t = clamp(perceptual_roughness * S(n - 1), S(0), S(n - 1));
        int ti = int(value_of(t));
        j0 = ti < n - 1 ? ti : n - 2;
        j1 = j0 + 1;
        ty = F(t - S(j0));
    }

    // Channel c at NoV in [0, 1] (bilinear on the end-point grid).
    F operator()(F NoV, int c) const {
        F t = clamp(NoV * F(size - 1), F(0), F(size - 1));
        int i0 = int(value_of(t)) < size - 1 ? int(value_of(t)) : size - 2;
        F tx = t - F(i0);
        int k0 = 3 * (size * j0 + i0) + c, k1 = 3 * (size * j1 + i0) + c;
        F a = lerp(tx, at(k0), at(k0 + 3));
        F b = lerp(tx, at(k1), at(k1 + 3));
        return lerp(ty, a, b);
    }

    // The same lookup on an evaluation type V (F, a packet of F, or a Dual): the index arithmetic
    // is exact in V and a packet gathers the four entries per lane; a NaN NoV reads column 0.
    // Bit-identical to operator() for scalars.
    template <typename V> V lookup(V NoV, int c) const {
        V t = min_(max_(NoV * V(size - 1), V(0)), V(size - 1));
        V i0 = min_(floor(t), V(size - 2));
        V tx = t - i0;
        V k0 = V(3) * i0 + V(3 * size * j0 + c), k1 = V(3) * i0 + V(3 * size * j1 + c);
        V a = lerp(tx, gather_index(data, k0), gather_index(data + 3, k0));
        V b = lerp(tx, gather_index(data, k1), gather_index(data + 3, k1));
        return lerp(V(ty), a, b);
    }

    // Table entry k, read through its bits: an integer load cannot alias the float output
    // arrays of the batch kernels, which lets the vectorizer gather from the table.
    F at(int k) const {
        using T = scalar_t<F>;
        using U = std::conditional_t<std::is_same_v<T, float>, uint32_t, uint64_t>;
        return F(__builtin_bit_cast(T, reinterpret_cast<const U *>(data)[k]));
    }
};

} // namespace bsdfkit
