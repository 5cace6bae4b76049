/* mf_prefilter_gate.c -- the prefilter's gate before export (mf_prefilter.h: mf_prefilter_gate_*):
 * energy, NaN, parent vs children, view and texel spikes of the lobes' shading, and (with the
 * normal map) the continuity of the lobes' error against the per-texel reference shading
 * [Nahmias 2022, Ch. 3; docs/prefilter.md, "Gate"].  Moved from mf_prefilter.c unchanged. */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_prefilter.h"

#include "mf_prefilter_internal.h"

#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- the gate ---------------------------------------------------------------------------------- */

void mf_prefilter_gate_bounds_default(mf_prefilter_gate *g)
{
    memset(g, 0, sizeof *g);
    g->max_energy = MF_PREFILTER_GATE_ENERGY;
    g->max_level = MF_PREFILTER_GATE_LEVEL;
    g->max_view_spike = MF_PREFILTER_GATE_VIEW_SPIKE;
    g->max_texel_spike = MF_PREFILTER_GATE_TEXEL_SPIKE;
    g->max_cont_texel = MF_PREFILTER_GATE_CONT_TEXEL;
    g->max_cont_view = MF_PREFILTER_GATE_CONT_VIEW;
    g->max_cont_grazing = MF_PREFILTER_GATE_CONT_GRAZING;
    g->max_cont_lambert = MF_PREFILTER_GATE_CONT_LAMBERT;
}

/* The gate's lights, in the view-azimuth-aligned frame of view theta: quads of half-width
 * 0.05, 0.2, 0.8 (tangent-plane units) about the mirror direction (-sin theta, 0, cos theta) and
 * about the normal. */
#define GATE_NLIGHTS 6

static void gate_lights(double theta, mf_polygon *out)
{
    for (int k = 0; k < GATE_NLIGHTS; ++k) {
        double h = 0.05 * pow(4.0, k % 3), tl = k < 3 ? theta : 0.0;
        mf_vec3 c = mf_vec3_make(-sin(tl), 0.0, cos(tl));
        mf_vec3 t1 = mf_vec3_make(cos(tl), 0.0, sin(tl)), t2 = mf_vec3_make(0.0, 1.0, 0.0);
        static const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
        mf_vec3 v[4];
        for (int i = 0; i < 4; ++i)
            v[i] = mf_vec3_add(c, mf_vec3_add(mf_vec3_scale(t1, h * sx[i]), mf_vec3_scale(t2, h * sy[i])));
        out[k] = mf_polygon_make(4, v);
    }
}

/* magnitude * the LTC integral of each gate light; NAN where the matrix is not invertible. */
static void gate_shade(const float *m9, float mag, const mf_polygon *lights, double *s)
{
    mf_mat3 m;
    for (int i = 0; i < 9; ++i)
        m.m[i / 3][i % 3] = m9[i];
    mf_ltc ltc;
    int ok = mf_ltc_init(&ltc, m) == MF_OK;
    for (int k = 0; k < GATE_NLIGHTS; ++k)
        s[k] = ok ? mag * mf_ltc_integrate_polygon(&ltc, &lights[k], MF_POLYGON_ONE_SIDED) : NAN;
}

static void gate_worst(double v, double *worst, char *where, size_t n, const char *what, int level, int row, int col,
                       int a, int b)
{
    if (v > *worst) {
        *worst = v;
        snprintf(where, n, "%s at level %d, texel (%d, %d), view (%d, %d)", what, level, col, row, a, b);
    }
}

/* mf_prefilter_gate_run; with S_out, the lobes' shading of every level is handed to the caller
 * (S_out[l][GATE_NLIGHTS * entry + light]; free each and the array) instead of freed. */
static mf_status gate_core(const mf_prefilter_level *levels, int nlevels, mf_prefilter_gate *g, double ***S_out)
{
    if (!levels || nlevels < 1 || !g)
        return MF_ERR_DOMAIN;
    g->nan_entries = 0;
    g->worst_energy = g->worst_level = g->worst_view_spike = g->worst_texel_spike = 0.0;
    g->where_energy[0] = g->where_level[0] = g->where_view[0] = g->where_texel[0] = '\0';
    int nt = levels[0].n_theta, np = levels[0].n_phi, nv = nt * np;
    mf_polygon *lights = malloc(sizeof *lights * GATE_NLIGHTS * (size_t)nt);
    double *sh = NULL;
    if (!lights)
        return MF_ERR_ALLOC;
    for (int a = 0; a < nt; ++a)
        gate_lights(a / (double)(nt - 1) * MF_PREFILTER_THETA_MAX, lights + GATE_NLIGHTS * a);
    /* the shading of every entry of every level (levels are small next to the fits' cost) */
    double **S = calloc((size_t)nlevels, sizeof *S);
    mf_status st = S ? MF_OK : MF_ERR_ALLOC;
    for (int l = 0; l < nlevels && st == MF_OK; ++l) {
        const mf_prefilter_level *lv = &levels[l];
        if (lv->n_theta != nt || lv->n_phi != np)
            st = MF_ERR_DOMAIN;
        size_t ne = (size_t)lv->width * lv->height * nv;
        if (st == MF_OK && !(S[l] = malloc(sizeof(double) * GATE_NLIGHTS * ne)))
            st = MF_ERR_ALLOC;
        for (size_t e = 0; st == MF_OK && e < ne; ++e) {
            int a = (int)(e / np % nt), b = (int)(e % np), t = (int)(e / nv);
            const float *m = lv->m + 9 * e;
            float mag = lv->magnitude[e];
            int bad = !isfinite(mag) || !(mag >= 0.0f);
            for (int i = 0; i < 9; ++i)
                bad |= !isfinite(m[i]);
            double n2 = (double)m[6] * m[6] + (double)m[7] * m[7] + (double)m[8] * m[8];
            if (!bad) {
                /* the lobe's albedo: magnitude * its mass above the horizon, (1 + n.z) / 2 with
                 * n = M^T z / |M^T z| (the clamped cosine over the half-space (M^T z).w > 0) */
                double frac = 0.5 * (1.0 + m[8] / sqrt(n2));
                double alb = lv->albedo ? lv->albedo[e] : mag;
                gate_worst(alb > 0.0 ? fabs(mag * frac / alb - 1.0) : fabs(mag * frac), &g->worst_energy, g->where_energy, sizeof g->where_energy,
                           "energy", lv->level, t / lv->width, t % lv->width, a, b);
            }
            gate_shade(m, mag, lights + GATE_NLIGHTS * a, S[l] + GATE_NLIGHTS * e);
            for (int k = 0; k < GATE_NLIGHTS; ++k)
                bad |= !isfinite(S[l][GATE_NLIGHTS * e + k]);
            g->nan_entries += bad;
        }
    }
    for (int l = 0; l < nlevels && st == MF_OK; ++l) {
        const mf_prefilter_level *lv = &levels[l];
        const double *s = S[l];
        for (int row = 0; row < lv->height; ++row)
            for (int col = 0; col < lv->width; ++col)
                for (int a = 0; a < nt; ++a)
                    for (int b = 0; b < np; ++b) {
                        size_t e = (((size_t)row * lv->width + col) * nt + a) * np + b;
                        double alb = fmax(lv->albedo ? lv->albedo[e] : lv->magnitude[e], 1e-6);
                        for (int k = 0; k < GATE_NLIGHTS; ++k) {
                            double x = s[GATE_NLIGHTS * e + k];
                            /* views: second differences along theta (interior) and phi (periodic) */
                            if (a > 0 && a + 1 < nt) {
                                double d = fabs(2.0 * x - s[GATE_NLIGHTS * (e - np) + k] - s[GATE_NLIGHTS * (e + np) + k]);
                                gate_worst(0.5 * d / alb, &g->worst_view_spike, g->where_view, sizeof g->where_view,
                                           "theta spike", lv->level, row, col, a, b);
                            }
                            if (np >= 3 && a > 0) {
                                size_t em = e - b + (b + np - 1) % np, ep = e - b + (b + 1) % np;
                                double d = fabs(2.0 * x - s[GATE_NLIGHTS * em + k] - s[GATE_NLIGHTS * ep + k]);
                                gate_worst(0.5 * d / alb, &g->worst_view_spike, g->where_view, sizeof g->where_view,
                                           "phi spike", lv->level, row, col, a, b);
                            }
                            /* texels: a lone texel above or below both neighbours along x or y */
                            for (int ax = 0; ax < 2; ++ax) {
                                int r0 = row - (ax == 1), r1 = row + (ax == 1), c0 = col - (ax == 0), c1 = col + (ax == 0);
                                if (r0 < 0 || c0 < 0 || r1 >= lv->height || c1 >= lv->width)
                                    continue;
                                double y0 = s[GATE_NLIGHTS * ((((size_t)r0 * lv->width + c0) * nt + a) * np + b) + k];
                                double y1 = s[GATE_NLIGHTS * ((((size_t)r1 * lv->width + c1) * nt + a) * np + b) + k];
                                double up = fmin(x - y0, x - y1), dn = fmin(y0 - x, y1 - x);
                                gate_worst(fmax(fmax(up, dn), 0.0) / alb, &g->worst_texel_spike, g->where_texel,
                                           sizeof g->where_texel, "texel spike", lv->level, row, col, a, b);
                            }
                            /* levels: the effective BRDF of a footprint is the mean of its four
                             * children's (equal areas), so the parent's shading is compared with
                             * the mean of the children's */
                            if (l > 0 && levels[l - 1].width == 2 * lv->width && levels[l - 1].height == 2 * lv->height) {
                                const mf_prefilter_level *cl = &levels[l - 1];
                                double m = 0.0;
                                for (int dy = 0; dy < 2; ++dy)
                                    for (int dx = 0; dx < 2; ++dx)
                                        m += S[l - 1][GATE_NLIGHTS * ((((size_t)(2 * row + dy) * cl->width + 2 * col + dx) * nt + a) * np + b) + k];
                                gate_worst(fabs(x - 0.25 * m) / alb, &g->worst_level, g->where_level, sizeof g->where_level,
                                           "parent vs children", lv->level, row, col, a, b);
                            }
                        }
                    }
    }
    if (S_out && st == MF_OK) {
        *S_out = S;
        S = NULL;
    }
    for (int l = 0; S && l < nlevels; ++l)
        free(S[l]);
    free(S), free(lights), free(sh);
    if (st != MF_OK)
        return st;
    g->pass_energy = g->worst_energy <= g->max_energy;
    g->pass_nan = g->nan_entries == 0;
    g->pass_level = g->worst_level <= g->max_level;
    g->pass_view = g->worst_view_spike <= g->max_view_spike;
    g->pass_texel = g->worst_texel_spike <= g->max_texel_spike;
    /* the view and texel spikes are reported, not gated: a coarse view grid and a sharp map give
     * genuine spikes (the V-groove's level-1 texels alternate between two tilts) */
    g->pass = g->pass_energy && g->pass_nan && g->pass_level;
    return MF_OK;
}

mf_status mf_prefilter_gate_run(const mf_prefilter_level *levels, int nlevels, mf_prefilter_gate *g)
{
    if (g)
        g->has_ref = 0, g->cont_gated = 0;
    return gate_core(levels, nlevels, g, NULL);
}

/* ---- the gate's reference: the effective BRDF's shading of the gate lights -------------------- */

/* The polygon clipped to z >= 0 (Sutherland-Hodgman on the vertices; the edges are great arcs,
 * i.e. straight segments seen from the origin, so the crossing of an edge with the plane z = 0
 * is a point of the arc on the horizon). */
static int clip_upper(const mf_polygon *p, mf_vec3 *out)
{
    int n = 0;
    for (int i = 0; i < p->n; ++i) {
        mf_vec3 a = p->v[i], b = p->v[(i + 1) % p->n];
        if (a.z >= 0.0)
            out[n++] = a;
        if ((a.z >= 0.0) != (b.z >= 0.0)) {
            double t = a.z / (a.z - b.z);
            mf_vec3 c = mf_vec3_add(a, mf_vec3_scale(mf_vec3_sub(b, a), t));
            c.z = 0.0;
            out[n++] = c;
        }
    }
    return n;
}

/* The base lobe's isotropic LTC against u = sqrt(1 - cos theta): per node (a, b, d, magnitude) of
 * M = [[a, 0, b], [0, 1, 0], [d, 0, e]] (M / M11 of the fit; e follows the same scaling). */
typedef struct {
    int lambert;
    double v[MF_PREFILTER_GATE_REF_N][5]; /* a, b, d, e, magnitude */
} gate_iso;

static mf_status gate_iso_fit(const mf_prefilter_options *o, gate_iso *t)
{
    memset(t, 0, sizeof *t);
    t->lambert = o->base == MF_PREFILTER_BASE_LAMBERT;
    if (t->lambert)
        return MF_OK;
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    if (!ggx)
        return MF_ERR_INTERNAL;
    mf_ltcfit_options fo;
    mf_ltcfit_options_default(&fo);
    double start[9], *sp = NULL;
    for (int i = 0; i < MF_PREFILTER_GATE_REF_N; ++i) {
        double u = i / (double)(MF_PREFILTER_GATE_REF_N - 1), c = fmax(1.0 - u * u, cos(MF_LTC_THETA_MAX));
        mf_ltcfit_entry e;
        mf_status st = mf_ltcfit_entry_fit(ggx, o->alpha, c, sp, &fo, &e);
        if (st != MF_OK)
            return st;
        double s = e.m[4];
        if (!(s > 0.0) || !isfinite(e.magnitude))
            return MF_ERR_INTERNAL;
        t->v[i][0] = e.m[0] / s, t->v[i][1] = e.m[2] / s, t->v[i][2] = e.m[6] / s, t->v[i][3] = e.m[8] / s;
        t->v[i][4] = e.magnitude;
        memcpy(start, e.m, sizeof start);
        sp = start;
    }
    return MF_OK;
}

/* The shading of the (already horizon-clipped, texel-frame, view-azimuth-0) polygon by the base
 * lobe at the texel-frame view cosine c. */
static double gate_iso_shade(const gate_iso *t, double c, const mf_polygon *p)
{
    if (t->lambert)
        return mf_polygon_integrate_cosine(p, MF_POLYGON_ONE_SIDED);
    double u = sqrt(fmax(0.0, 1.0 - c)) * (MF_PREFILTER_GATE_REF_N - 1);
    int i = (int)u;
    if (i > MF_PREFILTER_GATE_REF_N - 2)
        i = MF_PREFILTER_GATE_REF_N - 2;
    double f = u - i, q[5];
    for (int k = 0; k < 5; ++k)
        q[k] = (1.0 - f) * t->v[i][k] + f * t->v[i + 1][k];
    mf_mat3 m = {{{q[0], 0.0, q[1]}, {0.0, 1.0, 0.0}, {q[2], 0.0, q[3]}}};
    mf_ltc ltc;
    if (mf_ltc_init(&ltc, m) != MF_OK)
        return NAN;
    return q[4] * mf_ltc_integrate_polygon(&ltc, p, MF_POLYGON_ONE_SIDED);
}

/* Adds w times the reference shading of level-0 texel normal n (tangent frame) at view (theta,
 * phi) of the GATE_NLIGHTS lights (aligned frame) to acc. */
static void gate_ref_texel(const gate_iso *t, const double *n, double theta, double phi, const mf_polygon *lights,
                           double w, double *acc)
{
    double cp = cos(phi), sp = sin(phi);
    double na[3] = {cp * n[0] + sp * n[1], -sp * n[0] + cp * n[1], n[2]}; /* R_z(-phi) n */
    double r[9];
    mf_prefilter_min_rotation(na, r);
    mf_vec3 wo = mf_vec3_make(sin(theta), 0.0, cos(theta));
    mf_vec3 vq = mf_prefilter_texel_view(r, wo);
    double h = sqrt(vq.x * vq.x + vq.y * vq.y), ca = h > 0.0 ? vq.x / h : 1.0, sa = h > 0.0 ? vq.y / h : 0.0;
    for (int k = 0; k < GATE_NLIGHTS; ++k) {
        mf_vec3 v[MF_POLYGON_MAX_VERTICES];
        int nv = clip_upper(&lights[k], v);
        if (nv < 3)
            continue;
        for (int i = 0; i < nv; ++i) {
            mf_vec3 x = mf_prefilter_rot_t(r, v[i]); /* texel frame, then its view azimuth turned to 0 */
            v[i] = mf_vec3_make(ca * x.x + sa * x.y, -sa * x.x + ca * x.y, x.z);
        }
        mf_polygon p = mf_polygon_make(nv, v);
        acc[k] += w * gate_iso_shade(t, vq.z, &p);
    }
}

/* Lone extreme of x against its two neighbours y0, y1 (0 unless above or below both). */
static double gate_lone(double x, double y0, double y1)
{
    return fmax(fmax(fmin(x - y0, x - y1), fmin(y0 - x, y1 - x)), 0.0);
}

mf_status mf_prefilter_gate_run_ref(const mf_prefilter_level *levels, int nlevels, const double *normals, int width,
                                    int height, const mf_prefilter_options *o, mf_prefilter_gate *g)
{
    if (!levels || nlevels < 1 || !g || !normals || !o || width < 1 || height < 1)
        return MF_ERR_DOMAIN;
    int nt = o->n_theta, np = o->n_phi, nv = nt * np;
    for (int l = 0; l < nlevels; ++l) {
        const mf_prefilter_level *lv = &levels[l];
        int k = l + 1, w = width >> k, h = height >> k;
        if (lv->level != k || lv->width != (w > 0 ? w : 1) || lv->height != (h > 0 ? h : 1) || lv->n_theta != nt ||
            lv->n_phi != np)
            return MF_ERR_DOMAIN;
    }
    double **S = NULL;
    mf_status st = gate_core(levels, nlevels, g, &S);
    if (st != MF_OK)
        return st;
    g->has_ref = 1;
    g->cont_gated = 0;
    g->worst_cont_grazing = 0.0;
    g->where_cont_grazing[0] = '\0';
    g->worst_cont_texel = g->worst_cont_view = g->worst_jump_texel = g->worst_jump_view = g->worst_ref_error = 0.0;
    g->where_cont_texel[0] = g->where_cont_view[0] = '\0';
    gate_iso *iso = malloc(sizeof *iso);
    mf_polygon *lights = malloc(sizeof *lights * GATE_NLIGHTS * (size_t)nt);
    double **R = calloc((size_t)nlevels, sizeof *R);
    if (!iso || !lights || !R)
        st = MF_ERR_ALLOC;
    if (st == MF_OK)
        st = gate_iso_fit(o, iso);
    for (int a = 0; st == MF_OK && a < nt; ++a)
        gate_lights(mf_prefilter_theta(o, a), lights + GATE_NLIGHTS * a);
    /* the reference: level 1 from its texels, each level above as the mean of its children */
    for (int l = 0; st == MF_OK && l < nlevels; ++l) {
        const mf_prefilter_level *lv = &levels[l];
        size_t ne = (size_t)lv->width * lv->height * nv;
        if (!(R[l] = calloc(GATE_NLIGHTS * ne, sizeof(double)))) {
            st = MF_ERR_ALLOC;
            break;
        }
        int cw = l ? levels[l - 1].width : width, ch = l ? levels[l - 1].height : height;
        for (int row = 0; row < lv->height; ++row)
            for (int col = 0; col < lv->width; ++col) {
                int nc = 0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx)
                        nc += 2 * row + dy < ch && 2 * col + dx < cw;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx) {
                        int cr = 2 * row + dy, cc = 2 * col + dx;
                        if (cr >= ch || cc >= cw)
                            continue;
                        for (int a = 0; a < nt; ++a)
                            for (int b = 0; b < np; ++b) {
                                size_t e = (((size_t)row * lv->width + col) * nt + a) * np + b;
                                double *acc = R[l] + GATE_NLIGHTS * e;
                                if (l == 0) {
                                    gate_ref_texel(iso, normals + 3 * ((size_t)cr * width + cc), mf_prefilter_theta(o, a),
                                                   mf_prefilter_phi(o, b), lights + GATE_NLIGHTS * a, 1.0 / nc, acc);
                                } else {
                                    const double *c = R[l - 1] + GATE_NLIGHTS * ((((size_t)cr * cw + cc) * nt + a) * np + b);
                                    for (int k = 0; k < GATE_NLIGHTS; ++k)
                                        acc[k] += c[k] / nc;
                                }
                            }
                    }
            }
    }
    /* e = S - R, then the continuity measures */
    for (int l = 0; st == MF_OK && l < nlevels; ++l) {
        const mf_prefilter_level *lv = &levels[l];
        size_t ne = (size_t)lv->width * lv->height * nv;
        for (size_t i = 0; i < GATE_NLIGHTS * ne; ++i)
            S[l][i] -= R[l][i];
        const double *E = S[l];
        for (int row = 0; row < lv->height; ++row)
            for (int col = 0; col < lv->width; ++col)
                for (int a = 0; a < nt; ++a)
                    for (int b = 0; b < np; ++b) {
                        size_t e = (((size_t)row * lv->width + col) * nt + a) * np + b;
                        double alb = fmax(lv->albedo ? lv->albedo[e] : lv->magnitude[e], 1e-6);
                        /* grazing rows (cos theta < MF_PREFILTER_MULTISTART_COS) have their own bound */
                        int gr = cos(mf_prefilter_theta(o, a)) < MF_PREFILTER_MULTISTART_COS;
                        double *wv = gr ? &g->worst_cont_grazing : &g->worst_cont_view;
                        double *wt = gr ? &g->worst_cont_grazing : &g->worst_cont_texel;
                        char *pv = gr ? g->where_cont_grazing : g->where_cont_view;
                        char *pt = gr ? g->where_cont_grazing : g->where_cont_texel;
                        size_t nw = sizeof g->where_cont_view;
                        for (int k = 0; k < GATE_NLIGHTS; ++k) {
                            double x = E[GATE_NLIGHTS * e + k];
                            if (!isfinite(x))
                                continue; /* counted by the nan check */
                            gate_worst(fabs(x) / alb, &g->worst_ref_error, g->where_cont_view, 0, "", 0, 0, 0, 0, 0);
                            /* views */
                            size_t vn[4] = {0};
                            int has[4] = {a > 0, a + 1 < nt, np >= 3, np >= 2};
                            if (has[0])
                                vn[0] = e - np;
                            if (has[1])
                                vn[1] = e + np;
                            vn[2] = e - b + (b + np - 1) % np, vn[3] = e - b + (b + 1) % np;
                            for (int q = 0; q < 4; ++q)
                                if (has[q] && (q != 3 || np >= 3 || b == 0)) {
                                    double d = fabs(x - E[GATE_NLIGHTS * vn[q] + k]);
                                    double ab = fmax(alb, lv->albedo ? lv->albedo[vn[q]] : lv->magnitude[vn[q]]);
                                    gate_worst(d / ab, &g->worst_jump_view, g->where_cont_view, 0, "", 0, 0, 0, 0, 0);
                                }
                            if (has[0] && has[1])
                                gate_worst(gate_lone(x, E[GATE_NLIGHTS * vn[0] + k], E[GATE_NLIGHTS * vn[1] + k]) / alb,
                                           wv, pv, nw,
                                           "theta error spike", lv->level, row, col, a, b);
                            if (np >= 3 && a > 0)
                                gate_worst(gate_lone(x, E[GATE_NLIGHTS * vn[2] + k], E[GATE_NLIGHTS * vn[3] + k]) / alb,
                                           wv, pv, nw,
                                           "phi error spike", lv->level, row, col, a, b);
                            /* texels: periodic neighbours (normal maps tile) */
                            for (int ax = 0; ax < 2; ++ax) {
                                int n_ax = ax ? lv->height : lv->width;
                                if (n_ax < 2)
                                    continue;
                                int r1 = (row + (ax == 1)) % lv->height, c1 = (col + (ax == 0)) % lv->width;
                                int r0 = (row - (ax == 1) + lv->height) % lv->height, c0 = (col - (ax == 0) + lv->width) % lv->width;
                                size_t f1 = (((size_t)r1 * lv->width + c1) * nt + a) * np + b;
                                size_t f0 = (((size_t)r0 * lv->width + c0) * nt + a) * np + b;
                                double ab = fmax(alb, lv->albedo ? lv->albedo[f1] : lv->magnitude[f1]);
                                gate_worst(fabs(x - E[GATE_NLIGHTS * f1 + k]) / ab, &g->worst_jump_texel, g->where_cont_texel, 0,
                                           "", 0, 0, 0, 0, 0);
                                gate_worst(gate_lone(x, E[GATE_NLIGHTS * f0 + k], E[GATE_NLIGHTS * f1 + k]) / alb,
                                           wt, pt, nw,
                                           "texel error spike", lv->level, row, col, a, b);
                            }
                        }
                    }
    }
    for (int l = 0; l < nlevels; ++l) {
        free(S[l]);
        if (R)
            free(R[l]);
    }
    free(S), free(R), free(lights), free(iso);
    if (st != MF_OK)
        return st;
    /* GGX: reported, not gated (they do not separate good from corrupted runs); Lambert: gated
     * (mf_prefilter.h) */
    g->cont_gated = o->base == MF_PREFILTER_BASE_LAMBERT;
    g->pass_cont_texel = g->worst_cont_texel <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_texel);
    g->pass_cont_view = g->worst_cont_view <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_view);
    g->pass_cont_grazing = g->worst_cont_grazing <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_grazing);
    if (g->cont_gated)
        g->pass = g->pass && g->pass_cont_texel && g->pass_cont_view && g->pass_cont_grazing;
    return MF_OK;
}
