/* mfkit.h -- the whole pure C core of mfkit (lib/): include this or the module headers. */
#ifndef MFKIT_H
#define MFKIT_H

#include "mfkit/mf_core.h"
#include "mfkit/mf_rng.h"
#include "mfkit/mf_quad.h"
#include "mfkit/mf_ndf.h"
#include "mfkit/mf_smith.h"
#include "mfkit/mf_fresnel.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_albedo.h"
#include "mfkit/mf_energy.h"
#include "mfkit/mf_sample.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_ltc_lights.h"
#include "mfkit/mf_check.h"
#include "mfkit/mf_validate.h"
#include "mfkit/mf_table.h"
#include "mfkit/mf_sh.h"
#include "mfkit/mf_leadr.h"
#include "mfkit/mf_moments.h"
#include "mfkit/mf_filter.h"
#include "mfkit/mf_proxy.h"
#include "mfkit/mf_maps.h"

#include "mfkit/mf_ltc_table.h"
#include "mfkit/mf_model.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/mf_table_kind.h"
#include "mfkit/mf_walk.h"

#endif /* MFKIT_H */
