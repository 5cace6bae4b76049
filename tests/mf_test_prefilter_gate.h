/* Shared by the prefilter gate's tests and its measuring tool (test_prefilter_gate.c,
 * test_prefilter_gate_files.c): the corruption generator's LCG and the shading change a corruption
 * causes. */
#ifndef MF_TEST_PREFILTER_GATE_H
#define MF_TEST_PREFILTER_GATE_H

#include <math.h>
#include <stdint.h>

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return *s >> 33;
}

/* The largest change, over the gate's six lights (quads of half-width 0.05, 0.2, 0.8 about the mirror
 * direction and the normal, as mf_prefilter_gate.c places them), of the shading magnitude * LTC
 * integral of lobe e of level L (now corrupted) against its saved matrix and magnitude, / albedo. */
static double lobe_change(const mf_prefilter_level *L, size_t e, const float *saved, const mf_prefilter_options *o)
{
    int a = (int)(e / (size_t)o->n_phi % (size_t)o->n_theta);
    double th = mf_prefilter_theta(o, a), worst = 0.0;
    for (int k = 0; k < 6; ++k) {
        double h = 0.05 * pow(4.0, k % 3), tl = k < 3 ? th : 0.0;
        mf_vec3 c = mf_vec3_make(-sin(tl), 0.0, cos(tl)), t1 = mf_vec3_make(cos(tl), 0.0, sin(tl));
        mf_vec3 t2 = mf_vec3_make(0.0, 1.0, 0.0), v[4];
        static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
        for (int i = 0; i < 4; ++i)
            v[i] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(t1, h * sx[i]), mf_vec3_scale(t2, h * sy[i])));
        mf_polygon p = mf_polygon_make(4, v);
        double s[2];
        for (int t = 0; t < 2; ++t) {
            const float *m9 = t ? saved : L->m + 9 * e;
            float mag = t ? saved[9] : L->magnitude[e];
            mf_mat3 m;
            for (int i = 0; i < 9; ++i)
                m.m[i / 3][i % 3] = m9[i];
            mf_ltc ltc;
            s[t] = mf_ltc_init(&ltc, m) == MF_OK ? mag * mf_ltc_integrate_polygon(&ltc, &p, MF_POLYGON_ONE_SIDED) : INFINITY;
        }
        worst = fmax(worst, fabs(s[0] - s[1]) / fmax(L->albedo[e], 1e-6));
    }
    return worst;
}

#endif
