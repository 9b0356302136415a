// THE list of compiled models (pbrt-v4's BxDF TaggedPointer type list is the pattern). The
// bindings create bsdfkit._core.<Name> for each entry (cpp/bindings/bind_all.h, one translation unit per family list below, keyword
// arguments named as the Params fields) and the renderer's Material is the variant over it
// (render/material.h), so a bound model can always be rendered. Adding a model: its header
// (core/bxdf.h states what it must have; the static_assert below checks it) and one entry in
// its family list here.
#pragma once
#include "../core/bxdf.h"
#include "conductor.h"
#include "dielectric.h"
#include "eon.h"
#include "diffuse.h"
#include "diffuse_transmission.h"
#include "filament.h"
#include "measured.h"
#include "merl.h"
#include "layered.h"
#include "layered_analytic.h"
#include "plastic.h"
#include "principled.h"
#include "openpbr.h"
#include "hair.h"
#include "normalized_fresnel.h"
#include "thin_dielectric.h"

namespace bsdfkit {

// One list per model family: the bindings compile each family in its own translation unit
// (cpp/bindings/models_bind_<family>.cpp); AllModels is their concatenation, in this order.
using PbrtModels = ModelList<DiffuseBxDF,
                             DiffuseTransmissionBxDF,
                             ConductorBxDF,             // Fresnel knob: one compiled class per variant
                             ConductorSchlickBxDF,
                             ConductorF82BxDF,
                             DielectricBxDF,
                             ThinDielectricBxDF,
                             EONBxDF>;                  // energy-preserving Oren-Nayar (OpenPBR's diffuse)
using FilamentModels = ModelList<FilamentStandardBxDF,  // with / without the clear-coat and sheen lobes
                                 FilamentStandardCoatBxDF,
                                 FilamentStandardSheenBxDF,
                                 FilamentStandardCoatSheenBxDF,
                                 FilamentClothBxDF>;
using MeasuredModels = ModelList<MERLNearestBxDF,       // measured: MERL table, nearest / trilinear lookup
                                 MERLLinearBxDF,
                                 MeasuredBxDF>;         // measured: RGL tensor file
using LayeredModels = ModelList<PlasticBxDF,
                                CoatedDiffuseBxDF,      // stochastic (pbrt-v4 LayeredBxDF)
                                CoatedConductorBxDF,
                                CoatedDiffuseAnalyticBxDF, // method="analytic" (Weidlich & Wilkie 2007)
                                CoatedConductorAnalyticBxDF>;
using HairModels = ModelList<NormalizedFresnelBxDF,
                             HairBxDF,
                             HairFarFieldBxDF>;         // Hair with h=None: Gauss-Legendre over h (nodes: a knob)
using ProductionModels = ModelList<PrincipledBxDF,      // Mitsuba 3 principled (Disney 2015)
                                   PrincipledThinBxDF,  // Mitsuba 3 principledthin
                                   OpenPBRBxDF>;        // OpenPBR Surface 1.1 (ASWF)

using AllModels =
    ModelListCat<PbrtModels, FilamentModels, MeasuredModels, LayeredModels, HairModels, ProductionModels>::type;

static_assert(AllModels::check(), "a model of AllModels does not follow core/bxdf.h");
static_assert(AllModels::names_unique(), "two models of AllModels have the same Name");

} // namespace bsdfkit
