// The batch layer's policy table: how the batch kernels (batch.h, batch_spectral.h,
// batch_varying.h) and the preview renderer run each model, one line per model with its
// measured reason. Model headers hold physics and how it is written (Vectorized, lobe helpers);
// which model streams its stores, runs with denormals flushed or splits its sampler is decided
// here. A model without a line gets the default: plain stores, IEEE denormals.
//
// stream_outputs: a large call's eval / pdf outputs are written with streaming stores (batch.h,
//   kStreamMinBytes): only for kernels limited by memory traffic. Zen 4, tools/perf/loop_ab.py,
//   N = 1e6, outputs on lines (session 21): Diffuse eval 1.21-1.33x, sample 1.16-1.31x (1 / 2
//   threads); the delta lobes' eval (smooth Conductor and Dielectric, ThinDielectric; session 22)
//   1.23-1.50x, their pdf 0.96-1.09x. With every model streaming, NormalizedFresnel eval ran
//   0.59-0.64x, rough Plastic eval 0.75-0.90x, Hair sample 0.93x: streaming is not the default.
// stream_samples: the sampler streams too (default: as stream_outputs). The smooth Conductor,
//   Dielectric and ThinDielectric samplers ran 0.91-0.95x streamed at 1 thread, 1.00-1.06x at 2
//   (Zen 4, N = 1e6, session 22): they store plainly and their sample kernel is compiled once.
// instance_streams(m): per instance, whether eval / pdf stream (Conductor and Dielectric: only
//   when smooth; their rough lobes are limited by arithmetic).
// flush_denormals: the kernels run with FTZ | DAZ (core/simd.h, DenormalsFlushed). Hair: its
//   lobes' exponentials reach the denormals on ordinary pairs (narrow Mp tails times Np); FTZ |
//   DAZ made its eval kernel 14-21 % faster with identical outputs (tools/perf/throughput.py). A
//   model listed must tolerate a denormal operand read as 0.
#pragma once
#include <cstdint>
#include <type_traits>

namespace bsdfkit {

// The models with a line below (declared here so that the table does not depend on the order in
// which model headers are included; their definitions give the defaults).
enum class ConductorFresnel : uint8_t;
template <typename F, ConductorFresnel FR, int NC, typename C, typename A> struct ConductorBxDF;
template <typename F, typename Eta> struct DielectricBxDF;
template <typename F, typename Eta> struct ThinDielectricBxDF;
template <typename F, int NC, typename C> struct DiffuseBxDF;
template <typename F, int NC, typename C> struct DiffuseTransmissionBxDF;
template <typename F, int NC> struct HairBxDF;
template <typename F, int NC> struct HairFarFieldBxDF;
template <typename F> struct HairSpectral;
template <typename F> struct HairFarFieldSpectral;

struct DefaultPolicy {
    static constexpr bool stream_outputs = false;
    static constexpr bool stream_samples = false;
    static constexpr bool flush_denormals = false;
    template <typename M> static bool instance_streams(const M &) { return true; }
};
// Memory-bound eval / pdf and sampler.
struct StreamAll : DefaultPolicy {
    static constexpr bool stream_outputs = true;
    static constexpr bool stream_samples = true;
};
// Memory-bound eval / pdf when smooth (delta lobes); the sampler stores plainly.
struct StreamSmoothEvalPdf : DefaultPolicy {
    static constexpr bool stream_outputs = true;
    template <typename M> static bool instance_streams(const M &m) { return m.is_smooth(); }
};
// Memory-bound eval / pdf (zeros: a delta lobe only); the sampler stores plainly.
struct StreamEvalPdf : DefaultPolicy {
    static constexpr bool stream_outputs = true;
};
struct FlushDenormals : DefaultPolicy {
    static constexpr bool flush_denormals = true;
};

template <typename M> struct BatchPolicy : DefaultPolicy {};
// ---- the table: one line per model
template <typename F, int NC, typename C> struct BatchPolicy<DiffuseBxDF<F, NC, C>> : StreamAll {};
template <typename F, int NC, typename C> struct BatchPolicy<DiffuseTransmissionBxDF<F, NC, C>> : StreamAll {};
template <typename F, ConductorFresnel FR, int NC, typename C, typename A>
struct BatchPolicy<ConductorBxDF<F, FR, NC, C, A>> : StreamSmoothEvalPdf {};
template <typename F, typename Eta> struct BatchPolicy<DielectricBxDF<F, Eta>> : StreamSmoothEvalPdf {};
template <typename F, typename Eta> struct BatchPolicy<ThinDielectricBxDF<F, Eta>> : StreamEvalPdf {};
template <typename F, int NC> struct BatchPolicy<HairBxDF<F, NC>> : FlushDenormals {};
template <typename F, int NC> struct BatchPolicy<HairFarFieldBxDF<F, NC>> : FlushDenormals {};      // as HairBxDF
template <typename F> struct BatchPolicy<HairSpectral<F>> : FlushDenormals {};                     // as HairBxDF
template <typename F> struct BatchPolicy<HairFarFieldSpectral<F>> : FlushDenormals {};             // as HairBxDF

// The table as the kernels read it.
template <typename M> struct streams_outputs : std::bool_constant<BatchPolicy<M>::stream_outputs> {};
template <typename M> struct streams_samples : std::bool_constant<BatchPolicy<M>::stream_samples> {};
template <typename M> struct flushes_denormals : std::bool_constant<BatchPolicy<M>::flush_denormals> {};
template <typename M> inline bool instance_streams(const M &m) { return BatchPolicy<M>::instance_streams(m); }

} // namespace bsdfkit
