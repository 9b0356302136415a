// Piecewise-constant discrete distribution sampled in O(1) with Walker's alias method (Vose's
// construction, "A linear algorithm for generating random numbers with a given
// distribution", 1991). The environment map samples its pixel cells with it.
#pragma once
#include <cstdint>
#include <drjit/packet.h>
#include <vector>

namespace bsdfkit::render {

struct AliasTable {
    // One 8-byte entry per bin (8 bins per cache line): keep bin i if the remainder is below
    // threshold, else take alias. The bins' probabilities are not in the entry (the sampler
    // looks the chosen bin's probability up in its own data, see Environment::texels): the
    // table a sample walks is half the size.
    struct Entry {
        float threshold = 1.f;
        uint32_t alias = 0;
    };
    std::vector<Entry> entries;
    std::vector<float> pmfs;  // probability of each bin
    double total = 0;         // sum of the weights it was built from

    AliasTable() = default;
    // weights: n >= 1 non-negative finite values. All zero gives an empty (unsamplable) table.
    AliasTable(const float *w, size_t n) : entries(n), pmfs(n, 0.f) {
        for (size_t i = 0; i < n; ++i) total += double(w[i]);
        for (size_t i = 0; i < n; ++i) entries[i].alias = uint32_t(i);
        if (!(total > 0)) return;
        std::vector<double> scaled(n);
        std::vector<uint32_t> small, large;
        for (size_t i = 0; i < n; ++i) {
            pmfs[i] = float(double(w[i]) / total);
            scaled[i] = double(w[i]) / total * double(n);
            (scaled[i] < 1.0 ? small : large).push_back(uint32_t(i));
        }
        while (!small.empty() && !large.empty()) {
            uint32_t s = small.back(), l = large.back();
            small.pop_back();
            large.pop_back();
            entries[s].threshold = float(scaled[s]);
            entries[s].alias = l;
            scaled[l] -= 1.0 - scaled[s];
            (scaled[l] < 1.0 ? small : large).push_back(l);
        }
        // Leftovers are 1 up to rounding: they keep themselves.
        for (uint32_t i : small) entries[i].threshold = 1.f;
        for (uint32_t i : large) entries[i].threshold = 1.f;
    }

    bool empty() const { return !(total > 0); }
    size_t size() const { return entries.size(); }
    float pmf(size_t i) const { return pmfs[i]; }

    // Bin for u in [0, 1) (its probability is pmf(bin)); *remainder receives a fresh uniform in
    // [0, 1) from u's leftover bits.
    uint32_t sample(double u, double *remainder) const {
        size_t n = size();
        double x = u * double(n);
        size_t i = size_t(x);
        i = i < n ? i : n - 1;
        const Entry &e = entries[i];
        double frac = x - double(i);
        double t = e.threshold;
        bool keep = frac < t;
        double r = keep ? frac / t : (frac - t) / (1.0 - t);
        *remainder = r < 1.0 ? (r > 0.0 ? r : 0.0) : 0x1.fffffffffffffp-1;
        return keep ? uint32_t(i) : e.alias;
    }

    // sample() on packets (D: a double packet, I: its int32 packet), lane by lane the same
    // arithmetic: one division per lane (the one the scalar branch takes).
    template <typename D, typename I> I sample(const D &u, D *remainder) const {
        const int n = int(size());
        D x = u * D(double(n));
        I i = drjit::minimum(I(x), I(n - 1));  // x >= 0: the conversion truncates as size_t(x)
        const void *base = static_cast<const void *>(entries.data());
        using F = drjit::float32_array_t<D>;
        D t = D(drjit::gather<F>(base, i * I(2)));  // Entry: threshold, alias
        I alias = drjit::gather<I>(base, i * I(2) + I(1));
        D frac = x - D(i);
        auto keep = frac < t;
        D r = drjit::select(keep, frac, frac - t) / drjit::select(keep, t, D(1.0) - t);
        *remainder = drjit::select(r < D(1.0), drjit::select(r > D(0.0), r, D(0.0)), D(0x1.fffffffffffffp-1));
        return drjit::select(keep, i, alias);
    }
};

} // namespace bsdfkit::render
