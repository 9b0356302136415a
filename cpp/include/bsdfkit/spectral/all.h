// Every spectral form (core/bxdf.h `Spectral`): the adapters the models of bxdfs/all.h name.
// The model headers declare their form; its definition is here (batch_spectral.h and the
// family headers beside this one), included where the forms are bound or rendered.
#pragma once
#include "../batch_spectral.h"
#include "../bxdfs/all.h"
#include "hair_spectral.h"
#include "layered_spectral.h"
#include "measured_spectral.h"
