// The model concept, written down once and checked at compile time (pbrt-v4 base/bxdf.h is the
// pattern: one interface, one list of models; here the list is bxdfs/all.h).
//
// A model is a class template on the floating-point type F (float or double) with:
//   using Params = XParams;                   named parameters, one struct shared by both
//                                             precisions (and by a model's compiled variants):
//     template <class V> void fields(V &&v)   { v("eta", eta); v("alpha_x", alpha_x); ... }
//                                             field types: double, bool, int, an enum with an
//                                             enum_names() overload, std::array<double, 3> (RGB),
//                                             SharedTable<T> (a large read-only table, core/table.h);
//                                             the defaults are the defaults of the Python class.
//                                             Differentiable models template it on the scalar S
//                                             of their continuous fields (XParamsT<param_t<F>>:
//                                             double here, a Dual for eval_grad, core/dual.h).
//   static constexpr const char *Name         the compiled class's name (bsdfkit._core.<Name>)
//   static X make(const Params &)             parameters validated by the caller (Python)
//   uint8_t flags() const                                             BxDFFlags of the lobes
//   Spectrum<F> f(wo, wi, TransportMode) const                        cosine excluded
//   BSDFSample<F> sample_f(wo, F uc, Point2<F> u, TransportMode, uint8_t sample_flags) const
//   F pdf(wo, wi, TransportMode, uint8_t sample_flags) const          per unit solid angle
//   void regularize()
// Optional, for a sample_f that branches on a per-model (loop-invariant) smoothness test, so
// that the batch kernels run one branch-free loop per case (batch.h):
//   bool is_smooth() const
//   BSDFSample<F> sample_smooth(wo, F uc, TransportMode, uint8_t sample_flags) const
//   BSDFSample<F> sample_rough(wo, F uc, Point2<F> u, TransportMode, uint8_t sample_flags) const
// Storage: the model is trivially copyable (the batch kernels copy it per chunk, so its
// parameters stay in registers). A model holding a large read-only resource instead derives
// from a trivially copyable `using Kernel = ...` base that has every method above, and adds
// the SharedTable that keeps the resource alive (core/table.h; bxdfs/filament.h does this).
// Stochastic models also set BSDFSample::pdf_is_proportional.
// Capabilities, each a trait the one list (bxdfs/all.h) reads, never a second list of models:
//   using Spectral = XSpectral<F>;            its spectral form (wavelengths= calls and the
//                                             spectral renderer): an adapter with the shape of
//                                             batch_spectral.h's, built by
//                                             `template <class A> static XSpectral make(const Params &, const A &)`
//                                             (A: the spectral parameters by name, spectral/args.h).
//                                             The bindings create _core.<Name>Spectral from it and
//                                             the renderer's SpectralMaterial is the variant over them.
//   static constexpr int GradColumns = K;     eval_grad with up to K gradient columns (its
//                                             Params templated on param_t<F>; cpp/bindings/models_grad.cpp).
//   static Lanes make_lanes(const Params *p)  optional, a vectorized model's per-lane form for
//                                             per-element parameters (batch_varying.h): lane l
//                                             built from p[l] with make(p[l])'s operations.
//
// check_bxdf<Model>() states each rule as a static_assert with a readable message; bxdfs/all.h
// applies it to every model of the list.
#pragma once
#include <array>
#include <cstdint>
#include <type_traits>
#include <utility>
#include <variant>

#include "bsdf_sample.h"
#include "table.h"

namespace bsdfkit {

// The trivially copyable part of a model: its `Kernel` base if it names one, else the model.
template <typename M, typename = void> struct KernelOf { using type = M; };
template <typename M> struct KernelOf<M, std::void_t<typename M::Kernel>> { using type = typename M::Kernel; };
template <typename M> using KernelOf_t = typename KernelOf<M>::type;

// Whether a model splits sample_f into sample_smooth / sample_rough (see above).
template <typename M, typename = void> struct has_split_sample : std::false_type {};
template <typename M>
struct has_split_sample<M, std::void_t<decltype(&M::is_smooth)>> : std::true_type {};
// (check_bxdf requires sample_smooth / sample_rough of a model with is_smooth(); they may be
// member templates on the evaluation type, which have no address to test.)

// Whether a model runs on packets in the batch kernels (batch.h): `static constexpr bool
// Vectorized = true;` and every method a template on the evaluation type V (core/simd.h).
template <typename M, typename = void> struct is_vectorized : std::false_type {};
template <typename M> struct is_vectorized<M, std::void_t<decltype(M::Vectorized)>> : std::bool_constant<M::Vectorized> {};

// Whether a model declares a spectral form (`using Spectral = ...`; above).
template <typename M, typename = void> struct has_spectral : std::false_type {};
template <typename M> struct has_spectral<M, std::void_t<typename M::Spectral>> : std::true_type {};

// The largest number of gradient columns of a differentiable model (`GradColumns`), 0 for others.
template <typename M, typename = void> struct grad_columns : std::integral_constant<int, 0> {};
template <typename M>
struct grad_columns<M, std::void_t<decltype(M::GradColumns)>> : std::integral_constant<int, int(M::GradColumns)> {};

// An enum field of a Params struct names its values by an overload found by argument-dependent
// lookup:  inline constexpr std::array<const char *, 2> enum_names(Masking) { return {...}; }
// (value i is named names[i]); the bindings accept the name or the integer.
template <typename E, typename = void> struct has_enum_names : std::false_type {};
template <typename E>
struct has_enum_names<E, std::void_t<decltype(enum_names(E{}))>> : std::true_type {};

namespace detail {

struct nonesuch {};
template <typename, template <typename...> class Op, typename... Args> struct detector { using type = nonesuch; };
template <template <typename...> class Op, typename... Args>
struct detector<std::void_t<Op<Args...>>, Op, Args...> { using type = Op<Args...>; };
template <typename Expected, template <typename...> class Op, typename... Args>
inline constexpr bool returns = std::is_same_v<Expected, typename detector<void, Op, Args...>::type>;
template <template <typename...> class Op, typename... Args>
inline constexpr bool detected = !std::is_same_v<nonesuch, typename detector<void, Op, Args...>::type>;

template <typename F> const Vec3<F> &vec();
template <typename M> using flags_t = decltype(std::declval<const M &>().flags());
template <typename M, typename F>
using f_t = decltype(std::declval<const M &>().f(vec<F>(), vec<F>(), TransportMode::Radiance));
template <typename M, typename F>
using sample_f_t = decltype(std::declval<const M &>().sample_f(vec<F>(), F(), Point2<F>(), TransportMode::Radiance,
                                                                uint8_t()));
template <typename M, typename F>
using pdf_t = decltype(std::declval<const M &>().pdf(vec<F>(), vec<F>(), TransportMode::Radiance, uint8_t()));
template <typename M> using regularize_t = decltype(std::declval<M &>().regularize());
template <typename M> using is_smooth_t = decltype(std::declval<const M &>().is_smooth());
template <typename M, typename F>
using sample_smooth_t =
    decltype(std::declval<const M &>().sample_smooth(vec<F>(), F(), TransportMode::Radiance, uint8_t()));
template <typename M, typename F>
using sample_rough_t = decltype(std::declval<const M &>().sample_rough(vec<F>(), F(), Point2<F>(),
                                                                        TransportMode::Radiance, uint8_t()));
template <typename M> using params_t = typename M::Params;
template <typename M> using make_t = decltype(M::make(std::declval<const typename M::Params &>()));
template <typename M> using name_t = decltype(M::Name);
struct AnyVisitor {
    template <typename T> void operator()(const char *, T &) const {}
};
template <typename P> using fields_t = decltype(std::declval<P &>().fields(AnyVisitor{}));

// The field types the bindings know how to convert.
template <typename T> struct is_array3 : std::false_type {};
template <> struct is_array3<std::array<double, 3>> : std::true_type {};
struct FieldTypeCheck {
    template <typename T> void operator()(const char *, T &) const {
        static_assert(std::is_same_v<T, double> || std::is_same_v<T, bool> || std::is_same_v<T, int> ||
                          is_array3<T>::value || is_shared_table<T>::value ||
                          (std::is_enum_v<T> && has_enum_names<T>::value),
                      "Params field: its type must be double, bool, int, std::array<double, 3>, SharedTable<T> or "
                      "an enum with an enum_names() overload");
    }
};

constexpr bool same_name(const char *a, const char *b) {
    while (*a && *a == *b) ++a, ++b;
    return *a == *b;
}

} // namespace detail

// The rules for one precision.
template <typename M, typename F> constexpr bool check_bxdf_for() {
    using namespace detail;
    static_assert(detected<params_t, M>, "BxDF: needs a nested `using Params = ...` (named parameters)");
    static_assert(std::is_default_constructible_v<typename M::Params>,
                  "BxDF: Params must be default-constructible (its defaults are the model's defaults)");
    static_assert(detected<fields_t, typename M::Params>,
                  "BxDF: Params needs `template <class V> void fields(V &&v)` calling v(\"name\", field) per field");
    static_assert(detected<name_t, M>, "BxDF: needs `static constexpr const char *Name`");
    static_assert(returns<M, make_t, M>, "BxDF: needs `static Model make(const Params &)`");
    static_assert(returns<uint8_t, flags_t, M>, "BxDF: needs `uint8_t flags() const`");
    static_assert(returns<Spectrum<F>, f_t, M, F>,
                  "BxDF: needs `Spectrum<F> f(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode) const`");
    static_assert(returns<BSDFSample<F>, sample_f_t, M, F>,
                  "BxDF: needs `BSDFSample<F> sample_f(wo, F uc, Point2<F> u, TransportMode, uint8_t sample_flags) const`");
    static_assert(returns<F, pdf_t, M, F>,
                  "BxDF: needs `F pdf(const Vec3<F> &wo, const Vec3<F> &wi, TransportMode, uint8_t sample_flags) const`");
    static_assert(returns<void, regularize_t, M>, "BxDF: needs `void regularize()`");
    if constexpr (detected<is_smooth_t, M>) {
        static_assert(returns<bool, is_smooth_t, M>, "BxDF: is_smooth() const must return bool");
        static_assert(returns<BSDFSample<F>, sample_smooth_t, M, F>,
                      "BxDF with is_smooth(): needs `BSDFSample<F> sample_smooth(wo, F uc, TransportMode, uint8_t) const`");
        static_assert(returns<BSDFSample<F>, sample_rough_t, M, F>,
                      "BxDF with is_smooth(): needs `BSDFSample<F> sample_rough(wo, F uc, Point2<F> u, TransportMode, "
                      "uint8_t) const`");
    }
    static_assert(std::is_trivially_copyable_v<KernelOf_t<M>>,
                  "BxDF: the model (or its `Kernel` base, when it holds a SharedTable) must be trivially copyable");
    static_assert(std::is_base_of_v<KernelOf_t<M>, M>, "BxDF: a model's `Kernel` must be its base class");
    // Instantiates the field visitor with a checker of each field's type (never called).
    [[maybe_unused]] auto field_types = [] {
        typename M::Params p;
        p.fields(FieldTypeCheck{});
    };
    return true;
}

// The rules for both precisions, and one Params for both (the bindings build both from it).
template <template <typename> class M> constexpr bool check_bxdf() {
    static_assert(std::is_same_v<typename M<float>::Params, typename M<double>::Params>,
                  "BxDF: Params must not depend on F (declare it at namespace scope, `using Params = XParams;`)");
    return check_bxdf_for<M<float>, float>() && check_bxdf_for<M<double>, double>();
}

// A list of models (pbrt-v4's TaggedPointer<...> type list): the variant over them and a
// compile-time loop over them. bxdfs/all.h defines THE list, AllModels.
// VariantAppendIf<std::variant<std::monostate>, Models<F>...>::type: the variant of the Spectral form of
// each model that declares one...> (the spectral renderer's material).
template <typename V, typename... T> struct VariantAppendIf;
template <typename... A> struct VariantAppendIf<std::variant<A...>> { using type = std::variant<A...>; };
template <typename... A, typename M, typename... Rest> struct VariantAppendIf<std::variant<A...>, M, Rest...> {
    template <typename X, bool = has_spectral<X>::value> struct add { using type = std::variant<A...>; };
    template <typename X> struct add<X, true> { using type = std::variant<A..., typename X::Spectral>; };
    using type = typename VariantAppendIf<typename add<M>::type, Rest...>::type;
};

template <template <typename> class... Models> struct ModelList {
    template <typename F> using Variant = std::variant<Models<F>...>;
    template <typename F>
    using SpectralVariant = typename VariantAppendIf<std::variant<std::monostate>, Models<F>...>::type;
    static constexpr int size = int(sizeof...(Models));

    // fn.template apply<Model>() for each model in order. (A visitor with a member template,
    // not a tag carrying an alias template: an alias of a template with defaulted parameters,
    // such as ConductorBxDF<F, FR = Exact>, is a different template from it.)
    template <typename Fn> static void for_each(Fn &&fn) { (fn.template apply<Models>(), ...); }

    static constexpr bool check() { return (check_bxdf<Models>() && ...); }
    static constexpr bool names_unique() {
        const char *names[] = {Models<double>::Name...};
        for (int i = 0; i < size; ++i)
            for (int j = 0; j < i; ++j)
                if (detail::same_name(names[i], names[j])) return false;
        return true;
    }
};

// ModelListCat<ModelList<A...>, ModelList<B...>, ...>::type = ModelList<A..., B..., ...>.
template <class... Lists> struct ModelListCat;
template <template <typename> class... A> struct ModelListCat<ModelList<A...>> { using type = ModelList<A...>; };
template <template <typename> class... A, template <typename> class... B, class... Rest>
struct ModelListCat<ModelList<A...>, ModelList<B...>, Rest...> {
    using type = typename ModelListCat<ModelList<A..., B...>, Rest...>::type;
};

// ModelListSplit<ModelList<M...>, N>: ::head = the first N models, ::tail = the rest (the
// bindings split a large family over translation units without naming its models again).
template <class L, int N, class Head = ModelList<>, bool More = (N > 0)> struct ModelListSplit;
template <class L, class Head> struct ModelListSplit<L, 0, Head, false> {
    using head = Head;
    using tail = L;
};
template <template <typename> class M0, template <typename> class... T, int N, template <typename> class... H>
struct ModelListSplit<ModelList<M0, T...>, N, ModelList<H...>, true>
    : ModelListSplit<ModelList<T...>, N - 1, ModelList<H..., M0>> {};

} // namespace bsdfkit
