/* mf_prefilter_gate.c -- the prefilter's gate before export (mf_prefilter.h: mf_prefilter_gate_*):
 * energy, NaN, parent vs children, view and texel spikes of the lobes' shading, and (with the
 * normal map) the continuity of the lobes' error against the per-texel reference shading and the
 * lobes' own jumps against the reference's (excess, gated), and lobes copied, swapped or shifted
 * between texel, azimuth and elevation neighbours (own fit and own fit across elevations, gated)
 * [Nahmias 2022, Ch. 3; docs/prefilter.md, "Gate", "Gating continuity across texels", "Gating copied
 * lobes (own fit)" and "Own fit across elevations"]. */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/fit/mf_prefilter.h"

#include "mf_prefilter_internal.h"

#include "mfkit/fit/mf_ltcfit.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
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
    g->max_cont_cross = MF_PREFILTER_GATE_CONT_CROSS;
    g->max_cont_excess = MF_PREFILTER_GATE_CONT_EXCESS;
    g->max_cont_owner = MF_PREFILTER_GATE_OWN_FIT;
    g->max_cont_owner_theta = MF_PREFILTER_GATE_OWN_FIT_THETA;
}

/* The gate's lights, in the view-azimuth-aligned frame of view theta: quads of half-width
 * 0.05, 0.2, 0.8 (tangent-plane units) about the mirror direction (-sin theta, 0, cos theta) and
 * about the normal. */
#define GATE_NLIGHTS MF_PREFILTER_GATE_NLIGHTS

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

static int gate_ltc(const float *m9, mf_ltc *ltc) /* 1 when the row-major M is invertible */
{
    mf_mat3 m;
    for (int i = 0; i < 9; ++i)
        m.m[i / 3][i % 3] = m9[i];
    return mf_ltc_init(ltc, m) == MF_OK;
}

/* magnitude * the LTC integral of each gate light, summed over the entry's nl lobes (9 floats of m and
 * one magnitude each: two for a two-lobe table, mf_prefilter_gate_stream_set_lobes); NAN where a
 * matrix is not invertible. */
static void gate_shade(const float *m9, const float *mag, int nl, const mf_polygon *lights, double *s)
{
    for (int k = 0; k < GATE_NLIGHTS; ++k)
        s[k] = 0.0;
    for (int j = 0; j < nl; ++j) {
        mf_ltc ltc;
        int ok = gate_ltc(m9 + 9 * j, &ltc);
        for (int k = 0; k < GATE_NLIGHTS; ++k)
            s[k] += ok ? mag[j] * mf_ltc_integrate_polygon(&ltc, &lights[k], MF_POLYGON_ONE_SIDED) : NAN;
    }
}

/* Own fit across elevations: the lobe's shading (magnitude * LTC integral, as gate_shade) of the three
 * lights about the mirror direction (k < GATE_MIRROR) of its theta neighbours' views, lo (theta a - 1)
 * into x[0 .. 2] and hi (a + 1) into x[3 .. 5]; a NULL set is skipped (an edge row).  The lights about
 * the normal are the same at every elevation (gate_lights), so their shading is S's own. */
#define GATE_MIRROR 3

static void gate_shade_theta(const float *m9, const float *mag, int nl, const mf_polygon *lo, const mf_polygon *hi,
                             double *x)
{
    for (int k = 0; k < 2 * GATE_MIRROR; ++k)
        x[k] = 0.0;
    for (int j = 0; j < nl; ++j) {
        mf_ltc ltc;
        int ok = gate_ltc(m9 + 9 * j, &ltc);
        for (int q = 0; q < 2; ++q) {
            const mf_polygon *L = q ? hi : lo;
            for (int k = 0; k < GATE_MIRROR; ++k)
                x[GATE_MIRROR * q + k] +=
                    L && ok ? mag[j] * mf_ltc_integrate_polygon(&ltc, &L[k], MF_POLYGON_ONE_SIDED) : NAN;
        }
    }
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

/* The base lobe's LTC at the texel-frame view cosine c, and its magnitude: 1, or 0 when the matrix is
 * not invertible (the shading is then NaN).  Lambert has none (1). */
static int gate_iso_ltc(const gate_iso *t, double c, mf_ltc *ltc, double *mag)
{
    if (t->lambert)
        return 1;
    double u = sqrt(fmax(0.0, 1.0 - c)) * (MF_PREFILTER_GATE_REF_N - 1);
    int i = (int)u;
    if (i > MF_PREFILTER_GATE_REF_N - 2)
        i = MF_PREFILTER_GATE_REF_N - 2;
    double f = u - i, q[5];
    for (int k = 0; k < 5; ++k)
        q[k] = (1.0 - f) * t->v[i][k] + f * t->v[i + 1][k];
    mf_mat3 m = {{{q[0], 0.0, q[1]}, {0.0, 1.0, 0.0}, {q[2], 0.0, q[3]}}};
    *mag = q[4];
    return mf_ltc_init(ltc, m) == MF_OK;
}

/* The shading of the (already horizon-clipped, texel-frame, view-azimuth-0) polygon by the base
 * lobe (gate_iso_ltc's ok, ltc, mag at the texel-frame view cosine). */
static double gate_iso_shade(const gate_iso *t, int ok, const mf_ltc *ltc, double mag, const mf_polygon *p)
{
    if (t->lambert)
        return mf_polygon_integrate_cosine(p, MF_POLYGON_ONE_SIDED);
    if (!ok)
        return NAN;
    return mag * mf_ltc_integrate_polygon(ltc, p, MF_POLYGON_ONE_SIDED);
}

/* A gate light clipped to the aligned frame's upper half-space (clip_upper), once per view theta. */
typedef struct {
    int n;
    mf_vec3 v[MF_POLYGON_MAX_VERTICES];
} gate_clipped;

/* Adds w times the reference shading of level-0 texel normal n (tangent frame) at view (theta,
 * phi) of the GATE_NLIGHTS lights (aligned frame; clipped: the same clipped to z >= 0) to acc. */
static void gate_ref_texel(const gate_iso *t, const double *n, double theta, double phi, const gate_clipped *clipped,
                           double w, double *acc)
{
    double cp = cos(phi), sp = sin(phi);
    double na[3] = {cp * n[0] + sp * n[1], -sp * n[0] + cp * n[1], n[2]}; /* R_z(-phi) n */
    double r[9];
    mf_prefilter_min_rotation(na, r);
    mf_vec3 wo = mf_vec3_make(sin(theta), 0.0, cos(theta));
    mf_vec3 vq = mf_prefilter_texel_view(r, wo);
    double h = sqrt(vq.x * vq.x + vq.y * vq.y), ca = h > 0.0 ? vq.x / h : 1.0, sa = h > 0.0 ? vq.y / h : 0.0;
    mf_ltc ltc; /* the base lobe at this texel's view, shared by the lights */
    double mag = 0.0;
    int ok = -1;
    for (int k = 0; k < GATE_NLIGHTS; ++k) {
        int nv = clipped[k].n;
        if (nv < 3)
            continue;
        mf_vec3 v[MF_POLYGON_MAX_VERTICES];
        for (int i = 0; i < nv; ++i) {
            mf_vec3 x = mf_prefilter_rot_t(r, clipped[k].v[i]); /* texel frame, then its view azimuth turned to 0 */
            v[i] = mf_vec3_make(ca * x.x + sa * x.y, -sa * x.x + ca * x.y, x.z);
        }
        mf_polygon p = mf_polygon_make(nv, v);
        if (ok < 0)
            ok = gate_iso_ltc(t, vq.z, &ltc, &mag);
        acc[k] += w * gate_iso_shade(t, ok, &ltc, mag, &p);
    }
}

/* Lone extreme of x against its two neighbours y0, y1 (0 unless above or below both). */
static double gate_lone(double x, double y0, double y1)
{
    return fmax(fmax(fmin(x - y0, x - y1), fmin(y0 - x, y1 - x)), 0.0);
}

/* The reference R of columns [c0, c1) of row `row` of level index li (GATE_NLIGHTS doubles per entry,
 * R indexed as the whole row, C order): level 1 (li 0) from the level-0 normals of the cw x ch map
 * `normals` (its rows 2 row and 2 row + 1), each level above as the mean of its children, crow[dy]
 * being the child level's row 2 row + dy (NULL beyond its height ch; cw its width).  A footprint's
 * reference is the mean over its texels (Nahmias 2022, Eq. 2.36), summed child by child in row order.
 * The one definition of R: the streamed gate and the region tiles' (mf_prefilter_gate_reference) call
 * it with the same operands, so a tile's R read back is the stream's, bit for bit. */
static void gate_ref_cols(const gate_iso *iso, const gate_clipped *clipped, const mf_prefilter_options *o, int nt,
                          int np, int li, int row, int c0, int c1, const double *normals, const double *const crow[2],
                          int cw, int ch, double *R)
{
    const size_t nv = (size_t)nt * np;
    memset(R + GATE_NLIGHTS * (size_t)c0 * nv, 0, sizeof(double) * GATE_NLIGHTS * (size_t)(c1 - c0) * nv);
    for (int col = c0; col < c1; ++col) {
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
                        size_t i = ((size_t)col * nt + a) * np + b;
                        double *acc = R + GATE_NLIGHTS * i;
                        if (li == 0) {
                            gate_ref_texel(iso, normals + 3 * ((size_t)cr * cw + cc), mf_prefilter_theta(o, a),
                                           mf_prefilter_phi(o, b), clipped + GATE_NLIGHTS * a, 1.0 / nc, acc);
                        } else {
                            const double *c = crow[dy] + GATE_NLIGHTS * (((size_t)cc * nt + a) * np + b);
                            for (int k = 0; k < GATE_NLIGHTS; ++k)
                                acc[k] += c[k] / nc;
                        }
                    }
            }
    }
}

/* ---- the streamed gate ------------------------------------------------------------------------- */

/* The gate sees each level row by row, in an order where the rows a row's checks need are still
 * held (mf_prefilter_gate_stream_next): level l's row r comes right after the rows 2r and 2r + 1
 * of level l - 1 (its children, for the level check and the reference's mean).  Per level it
 * keeps five rows: rows 0 and 1 (the periodic texel neighbours of the last row, checked at the
 * end) and the last three (a row's texel checks run when the row after it arrives).  Per row and
 * entry: the lobe's shading S and the reference R of the GATE_NLIGHTS lights (doubles) and the
 * albedo the measures divide by (float).  Each worst keeps the key (level index, entry, light,
 * check) of its place, ties going to the smaller key: the order of a whole-level pass, so the
 * result (values and places) does not depend on the streaming order. */
#define GS_SLOTS 5
#define GS_MAX_THREADS 256

typedef struct {
    int level, w, h, fed;
    int twice; /* the level below (index - 1) is exactly twice as wide and as tall: the level check */
    size_t rowlen; /* entries per row: w * n_theta * n_phi */
    double *S[GS_SLOTS], *R[GS_SLOTS];
    float *A[GS_SLOTS];
    /* the gate across tiles: the map's level (gw x gh, growlen entries a row) and this stream's first
     * texel in it (gox, goy; 0 but in a region tile's part), for the keys and places; tw x th: a region
     * tile's texels at this level (rank 0's gs_ring) */
    int gw, gh, gox, goy, tw, th;
    size_t growlen;
} gs_level;

struct mf_prefilter_gate_stream {
    mf_prefilter_gate *g;
    int nl, nt, np, nv, ref, lambert;
    mf_prefilter_options o;
    const double *normals;
    int W, H;
    gs_level *L;
    mf_polygon *lights;
    gate_clipped *clipped; /* the lights clipped to z >= 0, per view theta (GATE_NLIGHTS each) */
    gate_iso *iso;
    uint64_t k_energy, k_level, k_view, k_texel, k_cont_texel, k_cont_view, k_cont_grazing, k_cont_cross, k_cont_excess;
    uint64_t k_cont_owner, k_cont_owner_view, k_cont_dominated, k_cont_owner_theta, k_cont_dominated_theta;
    /* own fit across elevations: scratch for one column's lobes under their theta neighbours' mirror
     * lights (2 * GATE_MIRROR doubles per view), one block of nv views per thread (xscr_all, threads
     * blocks, owned by the stream; xscr: this stream's or part's own block) */
    double *xscr_all, *xscr;
    int threads;           /* o->threads (1 without o), at most GS_MAX_THREADS */
    int half;              /* o->lobe != 0: a half table's gate (mf_prefilter_gate.half_table) */
    int nlobes;            /* lobes per entry in the rows fed (mf_prefilter_gate_stream_set_lobes; 1) */
    struct gs_part *parts; /* threads of them, reused for every row */
    /* the gate across tiles (docs/prefilter.md, "The gate across ranks"), mode:
     *   0 the whole gate;
     *   1 a region tile's part (mf_prefilter_gate_region): the stream holds the tile's levels, R given;
     *     every check of every entry but the texel checks of the tile's border entries (ring 1), unless
     *     the tile is the whole map;
     *   2 rank 0 with the region tiles' parts (mf_prefilter_gate_stream_begin_regions): at the region levels
     *     (index < nreg) R given, S computed for the two outer rings of each tile only, and only the
     *     texel checks of ring 1 run; the tiles' parts come in by mf_prefilter_gate_stream_merge */
    int mode, nreg, whole;
};

static size_t gs_part_size(void);

static int gs_slot(int r) { return r < 2 ? r : 2 + r % 3; }

/* The ring of a region tile that (row, col) of level L lies in: 1 its border, 2 the texels next to it,
 * 0 inside (tiles of tw x th texels at this level, from texel (0, 0)). */
static int gs_ring(const gs_level *L, int row, int col)
{
    int x = col % L->tw, y = row % L->th;
    int d = x < L->tw - 1 - x ? x : L->tw - 1 - x, dy = y < L->th - 1 - y ? y : L->th - 1 - y;
    d = d < dy ? d : dy;
    return d == 0 ? 1 : d == 1 ? 2 : 0;
}

int mf_prefilter_gate_ref_cols(int tw, int th, int y, int c[4])
{
    if (tw < 1 || th < 1 || y < 0 || y >= th || !c)
        return 0;
    /* gs_ring's rings 1 and 2: min(x, tw - 1 - x, y, th - 1 - y) <= 1 */
    int dy = y < th - 1 - y ? y : th - 1 - y;
    c[0] = 0, c[1] = tw, c[2] = c[3] = tw;
    if (dy <= 1 || tw <= 4)
        return 1;
    c[1] = 2, c[2] = tw - 2;
    return 2;
}

/* The key of (level index, entry, light, check): the order of a pass over levels, entries, lights
 * and the checks of one light (0 theta, 1 phi, 2 texels along x, 3 along y, 4 level). */
static uint64_t gs_key(int li, size_t e, int k, int c)
{
    return (uint64_t)li << 56 | (uint64_t)e << 8 | (uint64_t)k << 4 | (uint64_t)c;
}

static void gs_worst(double v, double *worst, uint64_t *wkey, uint64_t key, char *where, size_t n, const char *what,
                     int level, int row, int col, int a, int b)
{
    if (v > *worst || (v == *worst && *worst > 0.0 && key < *wkey)) {
        *worst = v, *wkey = key;
        memset(where, 0, n); /* the bytes after the string too: the same result bytes on any thread count */
        snprintf(where, n, "%s at level %d, texel (%d, %d), view (%d, %d)", what, level, col, row, a, b);
    }
}

static void gs_max(double v, double *worst)
{
    if (v > *worst)
        *worst = v;
}

void mf_prefilter_gate_stream_free(mf_prefilter_gate_stream *s)
{
    if (!s)
        return;
    for (int l = 0; s->L && l < s->nl; ++l)
        for (int i = 0; i < GS_SLOTS; ++i)
            free(s->L[l].S[i]), free(s->L[l].R[i]), free(s->L[l].A[i]);
    free(s->L), free(s->lights), free(s->clipped), free(s->iso), free(s->parts), free(s->xscr_all), free(s);
}

/* mf_prefilter_gate_stream_begin's work; ref: with the reference (normals, or R given with every row);
 * iso: fit the reference's base lobes (not needed when every row's R is given). */
static mf_status gs_begin(const mf_prefilter_level *shapes, int nlevels, const double *normals, int ref, int iso,
                          int width, int height, const mf_prefilter_options *o, mf_prefilter_gate *g,
                          mf_prefilter_gate_stream **out)
{
    if (out)
        *out = NULL;
    if (!shapes || nlevels < 1 || nlevels > 64 || !g || !out || (ref && (!o || width < 1 || height < 1)))
        return MF_ERR_DOMAIN;
    int nt = shapes[0].n_theta, np = shapes[0].n_phi;
    if (nt < 2 || np < 1 || (ref && (o->n_theta != nt || o->n_phi != np)))
        return MF_ERR_DOMAIN;
    for (int l = 0; l < nlevels; ++l) {
        const mf_prefilter_level *lv = &shapes[l];
        if (lv->n_theta != nt || lv->n_phi != np || lv->width < 1 || lv->height < 1)
            return MF_ERR_DOMAIN;
        int k = l + 1, w = width >> k, h = height >> k;
        if (ref && (lv->level != k || lv->width != (w > 0 ? w : 1) || lv->height != (h > 0 ? h : 1)))
            return MF_ERR_DOMAIN;
    }
    mf_prefilter_gate_stream *s = calloc(1, sizeof *s);
    if (!s)
        return MF_ERR_ALLOC;
    s->g = g, s->nl = nlevels, s->nt = nt, s->np = np, s->nv = nt * np, s->ref = ref;
    s->normals = normals, s->W = width, s->H = height;
    if (o)
        s->o = *o;
    s->lambert = s->ref && o->base == MF_PREFILTER_BASE_LAMBERT;
    s->half = o && o->lobe != 0;
    s->nlobes = 1;
    s->k_energy = s->k_level = s->k_view = s->k_texel = UINT64_MAX;
    s->k_cont_texel = s->k_cont_view = s->k_cont_grazing = s->k_cont_cross = s->k_cont_excess = UINT64_MAX;
    s->k_cont_owner = s->k_cont_owner_view = s->k_cont_dominated = UINT64_MAX;
    s->k_cont_owner_theta = s->k_cont_dominated_theta = UINT64_MAX;
    /* the results this run sets (as mf_prefilter_gate_run and _run_ref cleared them) */
    g->nan_entries = 0;
    g->worst_energy = g->worst_level = g->worst_view_spike = g->worst_texel_spike = 0.0;
    g->where_energy[0] = g->where_level[0] = g->where_view[0] = g->where_texel[0] = '\0';
    g->has_ref = s->ref, g->cont_gated = 0;
    if (s->ref) {
        g->worst_cont_grazing = 0.0;
        g->where_cont_grazing[0] = '\0';
        g->worst_cont_texel = g->worst_cont_view = g->worst_jump_texel = g->worst_jump_view = g->worst_ref_error = 0.0;
        g->where_cont_texel[0] = g->where_cont_view[0] = '\0';
        g->worst_cont_cross = g->worst_cont_cross_texel = 0.0;
        g->where_cont_cross[0] = '\0';
        g->worst_cont_excess = 0.0;
        g->where_cont_excess[0] = '\0';
        g->worst_cont_owner = g->worst_cont_owner_view = g->worst_cont_dominated = 0.0;
        g->where_cont_owner[0] = g->where_cont_owner_view[0] = g->where_cont_dominated[0] = '\0';
        g->worst_cont_owner_theta = g->worst_cont_dominated_theta = 0.0;
        g->where_cont_owner_theta[0] = g->where_cont_dominated_theta[0] = '\0';
    }
    s->threads = o && o->threads > 1 ? (o->threads < GS_MAX_THREADS ? o->threads : GS_MAX_THREADS) : 1;
    s->L = calloc((size_t)nlevels, sizeof *s->L);
    s->lights = malloc(sizeof *s->lights * GATE_NLIGHTS * (size_t)nt);
    s->parts = malloc(gs_part_size() * (size_t)s->threads);
    s->clipped = malloc(sizeof *s->clipped * GATE_NLIGHTS * (size_t)nt);
    if (s->ref)
        s->xscr_all = malloc(sizeof(double) * 2 * GATE_MIRROR * (size_t)s->nv * s->threads);
    s->xscr = s->xscr_all;
    mf_status st = s->L && s->lights && s->parts && s->clipped && (!s->ref || s->xscr_all) ? MF_OK : MF_ERR_ALLOC;
    for (int a = 0; st == MF_OK && a < nt; ++a)
        gate_lights(a / (double)(nt - 1) * MF_PREFILTER_THETA_MAX, s->lights + GATE_NLIGHTS * a);
    for (int q = 0; st == MF_OK && q < GATE_NLIGHTS * nt; ++q)
        s->clipped[q].n = clip_upper(&s->lights[q], s->clipped[q].v);
    for (int l = 0; st == MF_OK && l < nlevels; ++l) {
        gs_level *L = &s->L[l];
        const mf_prefilter_level *lv = &shapes[l];
        L->level = lv->level, L->w = lv->width, L->h = lv->height;
        L->twice = l > 0 && shapes[l - 1].width == 2 * lv->width && shapes[l - 1].height == 2 * lv->height;
        L->rowlen = (size_t)lv->width * s->nv;
        L->gw = L->tw = L->w, L->gh = L->th = L->h, L->growlen = L->rowlen; /* the whole map (mode 0) */
        int used[GS_SLOTS] = {0}; /* a level of fewer than GS_SLOTS rows uses fewer slots */
        for (int r = 0; r < lv->height && r < GS_SLOTS; ++r)
            used[gs_slot(r)] = 1;
        for (int i = 0; i < GS_SLOTS && st == MF_OK; ++i) {
            if (!used[i])
                continue;
            L->S[i] = malloc(sizeof(double) * GATE_NLIGHTS * L->rowlen);
            L->A[i] = malloc(sizeof(float) * L->rowlen);
            if (s->ref)
                L->R[i] = malloc(sizeof(double) * GATE_NLIGHTS * L->rowlen);
            if (!L->S[i] || !L->A[i] || (s->ref && !L->R[i]))
                st = MF_ERR_ALLOC;
        }
    }
    if (st == MF_OK && s->ref && iso) {
        s->iso = malloc(sizeof *s->iso);
        st = s->iso ? gate_iso_fit(o, s->iso) : MF_ERR_ALLOC;
    }
    if (st != MF_OK) {
        mf_prefilter_gate_stream_free(s);
        return st;
    }
    *out = s;
    return MF_OK;
}

mf_status mf_prefilter_gate_stream_begin(const mf_prefilter_level *shapes, int nlevels, const double *normals,
                                         int width, int height, const mf_prefilter_options *o, mf_prefilter_gate *g,
                                         mf_prefilter_gate_stream **out)
{
    return gs_begin(shapes, nlevels, normals, normals != NULL, 1, width, height, o, g, out);
}

mf_status mf_prefilter_gate_stream_begin_regions(const mf_prefilter_level *shapes, int nlevels, const double *normals,
                                                 int width, int height, int rw, int rh, int nreg,
                                                 const mf_prefilter_options *o, mf_prefilter_gate *g,
                                                 mf_prefilter_gate_stream **out)
{
    if (out)
        *out = NULL;
    if (!normals || nreg < 1 || nreg > nlevels || rw < 1 || rh < 1 || width < 1 || height < 1 || width % rw ||
        height % rh)
        return MF_ERR_DOMAIN;
    /* level 1 is a region level, so every level-1 R is given and the levels above take the mean of
     * their children's: the reference's base lobes are not needed */
    mf_prefilter_gate_stream *s;
    mf_status st = gs_begin(shapes, nlevels, normals, 1, 0, width, height, o, g, &s);
    if (st != MF_OK)
        return st;
    for (int l = 0; l < nreg; ++l) {
        gs_level *L = &s->L[l];
        int k = l + 1;
        L->tw = rw >> k > 0 ? rw >> k : 1, L->th = rh >> k > 0 ? rh >> k : 1;
        if (L->w % L->tw || L->h % L->th) {
            mf_prefilter_gate_stream_free(s);
            return MF_ERR_DOMAIN;
        }
    }
    s->mode = 2, s->nreg = nreg, s->whole = rw == width && rh == height;
    *out = s;
    return MF_OK;
}

int mf_prefilter_gate_stream_next(const mf_prefilter_gate_stream *s, int *level_index, int *row)
{
    if (!s)
        return 0;
    for (int l = s->nl - 1; l >= 0; --l) {
        const gs_level *L = &s->L[l];
        if (L->fed >= L->h)
            continue;
        if (l > 0) {
            const gs_level *C = &s->L[l - 1];
            int need = 2 * L->fed + 1 < C->h - 1 ? 2 * L->fed + 1 : C->h - 1; /* the last child row it reads */
            if (C->fed <= need)
                continue;
        }
        *level_index = l, *row = L->fed;
        return 1;
    }
    return 0;
}

/* The lobe's lone extreme beyond the effective BRDF's along one axis: x, y0, y1 the shading S of the
 * entry and of its two neighbours, r, r0, r1 their reference R.  The lobe's lone extreme upwards,
 * min(x - y0, x - y1), less the reference's own (when it has one upwards), and the same downwards;
 * 0 when neither is positive.  So a lobe may rise above (or dip below) both neighbours as far as the
 * effective BRDF does, and may smooth out the effective BRDF's own extremes (a single LTC does,
 * where a footprint's texel lobes straddle a light). */
static double gate_excess(double x, double y0, double y1, double r, double r0, double r1)
{
    double up = fmin(x - y0, x - y1) - fmax(fmin(r - r0, r - r1), 0.0);
    double dn = fmin(y0 - x, y1 - x) - fmax(fmin(r0 - r, r1 - r), 0.0);
    return fmax(fmax(up, dn), 0.0);
}

/* ---- own fit: lobes copied, swapped or shifted between neighbours ------------------------------
 * A lobe fitted to footprint F shades F's reference R to the fitting error; a lobe that landed on a
 * neighbouring entry (an exporter's indexing or tiling bug, a resumed run writing a tile one texel
 * off) shades its own footprint's reference there and the entry's only as well as the two
 * footprints' references agree.  So the check compares the entry's lobe with its neighbours'
 * references, and the neighbours' lobes with its reference (mf_prefilter.h). */
/* The one body of both: xS NULL is the same lights (the entry's lobe under j's lights is S). */
static void own_fit(int nlights, const double *S, const double *R, double albedo, int nn, const double *const *xS,
                    const double *const *nR, const double *const *yS, const double *nalb, mf_prefilter_gate_own *out)
{
    out->owner = out->dominated = 0.0;
    out->owner_at = out->dominated_at = -1;
    const double ia = 1.0 / fmax(albedo, 1e-6);
    double own = 0.0; /* |s - r|, the entry's own error */
    for (int k = 0; k < nlights; ++k) {
        double d = (S[k] - R[k]) * ia;
        if (!isfinite(d))
            return;
        own = fmax(own, fabs(d));
    }
    for (int j = 0; j < nn; ++j) {
        const double ja = 1.0 / fmax(nalb[j], 1e-6);
        double to = 0.0, from = 0.0; /* |x_j - r_j|, |y_j - r| (same lights: |s - r_j|, |s_j - r|) */
        int ok = 1;
        for (int k = 0; k < nlights; ++k) {
            double a = (xS ? xS[j][k] : S[k]) * ia - nR[j][k] * ja, b = yS[j][k] * ja - R[k] * ia;
            ok &= isfinite(a) && isfinite(b);
            to = fmax(to, fabs(a)), from = fmax(from, fabs(b));
        }
        if (!ok)
            continue;
        if (own - to > out->owner)
            out->owner = own - to, out->owner_at = j;
        if (own - from > out->dominated)
            out->dominated = own - from, out->dominated_at = j;
    }
}

void mf_prefilter_gate_own_fit(int nlights, const double *S, const double *R, double albedo, int nn,
                               const double *const *nS, const double *const *nR, const double *nalb,
                               mf_prefilter_gate_own *out)
{
    own_fit(nlights, S, R, albedo, nn, NULL, nR, nS, nalb, out);
}

void mf_prefilter_gate_own_fit_cross(int nlights, const double *S, const double *R, double albedo, int nn,
                                     const double *const *xS, const double *const *nR, const double *const *yS,
                                     const double *nalb, mf_prefilter_gate_own *out)
{
    own_fit(nlights, S, R, albedo, nn, xS, nR, yS, nalb, out);
}

/* The own-fit check's hook into the streamed gate: entry e (the map's row r and column col, for the
 * place; view (a, b)) of level
 * index li against its texel neighbours along x and y (tS, tR, albedos ta0, ta1; has_t) and its
 * azimuth neighbours vp[0], vp[1] in the row's arrays S, R, A (periodic; np >= 2). */
static void gs_own_fit(mf_prefilter_gate_stream *s, int li, int r, int col, int a, int b, size_t e, const double *Se,
                       const double *Re, double alb, const double *tS[2][2], const double *tR[2][2],
                       const double ta0[2], const double ta1[2], const int has_t[2], const size_t vp[2],
                       const double *S, const double *R, const float *A)
{
    static const char *what[6] = {"lobe shades the reference of texel x - 1 better than its own",
                                  "lobe shades the reference of texel x + 1 better than its own",
                                  "lobe shades the reference of texel y - 1 better than its own",
                                  "lobe shades the reference of texel y + 1 better than its own",
                                  "lobe shades the reference of view phi - 1 better than its own",
                                  "lobe shades the reference of view phi + 1 better than its own"};
    static const char *dwhat[6] = {"texel x - 1's lobe shades the reference better than its own",
                                   "texel x + 1's lobe shades the reference better than its own",
                                   "texel y - 1's lobe shades the reference better than its own",
                                   "texel y + 1's lobe shades the reference better than its own",
                                   "view phi - 1's lobe shades the reference better than its own",
                                   "view phi + 1's lobe shades the reference better than its own"};
    mf_prefilter_gate *g = s->g;
    const gs_level *L = &s->L[li];
    const double *nS[6], *nR[6];
    double na[6];
    int slot[6], nn = 0;
    for (int ax = 0; ax < 2; ++ax)
        if (has_t[ax])
            for (int q = 0; q < 2; ++q) {
                nS[nn] = tS[ax][q], nR[nn] = tR[ax][q], na[nn] = q ? ta1[ax] : ta0[ax], slot[nn] = 2 * ax + q;
                ++nn;
            }
    if (s->np >= 2)
        for (int q = 0; q < 2; ++q) {
            nS[nn] = S + GATE_NLIGHTS * vp[q], nR[nn] = R + GATE_NLIGHTS * vp[q], na[nn] = A[vp[q]], slot[nn] = 4 + q;
            ++nn;
        }
    /* two groups: the texel neighbours (owner, gated) and the azimuth neighbours (owner_view) */
    const int nt4 = 2 * (has_t[0] + has_t[1]), g0[2] = {0, nt4}, gn[2] = {nt4, nn - nt4};
    for (int grp = 0; grp < 2; ++grp) {
        if (gn[grp] < 1)
            continue;
        mf_prefilter_gate_own o;
        mf_prefilter_gate_own_fit(GATE_NLIGHTS, Se, Re, alb, gn[grp], nS + g0[grp], nR + g0[grp], na + g0[grp], &o);
        const int *sl = slot + g0[grp];
        if (o.owner_at >= 0) {
            if (grp == 0)
                gs_worst(o.owner, &g->worst_cont_owner, &s->k_cont_owner, gs_key(li, e, 0, 0), g->where_cont_owner,
                         sizeof g->where_cont_owner, what[sl[o.owner_at]], L->level, r, col, a, b);
            else
                gs_worst(o.owner, &g->worst_cont_owner_view, &s->k_cont_owner_view, gs_key(li, e, 0, 0),
                         g->where_cont_owner_view, sizeof g->where_cont_owner_view, what[sl[o.owner_at]], L->level, r,
                         col, a, b);
        }
        if (o.dominated_at >= 0)
            gs_worst(o.dominated, &g->worst_cont_dominated, &s->k_cont_dominated, gs_key(li, e, 0, grp),
                     g->where_cont_dominated, sizeof g->where_cont_dominated, dwhat[sl[o.dominated_at]], L->level, r,
                     col, a, b);
    }
}

/* Own fit across elevations (docs/prefilter.md, "Own fit across elevations"): column col of row `row` of
 * level index li, every view.  Each lobe is shaded under its theta neighbours' mirror lights
 * (gate_shade_theta, into the stream's scratch), then each entry is checked against its theta
 * neighbours (a - 1, a + 1: the same texel and azimuth) by mf_prefilter_gate_own_fit_cross, every
 * light judged at its own view: the entry's lobe and reference at its lights, the neighbour's at its. */
static void gs_own_fit_theta(mf_prefilter_gate_stream *s, int li, int row, int col, const float *m,
                             const float *magnitude, const double *S, const double *R, const float *A)
{
    static const char *what[2] = {"lobe shades the reference of view theta - 1 better than its own",
                                  "lobe shades the reference of view theta + 1 better than its own"};
    static const char *dwhat[2] = {"view theta - 1's lobe shades the reference better than its own",
                                   "view theta + 1's lobe shades the reference better than its own"};
    mf_prefilter_gate *g = s->g;
    const gs_level *L = &s->L[li];
    const int nt = s->nt, np = s->np, nv = s->nv, grow = L->goy + row, gcol = L->gox + col;
    const size_t c0 = (size_t)col * nv;
    double *X = s->xscr; /* per view: the lobe under theta a - 1's mirror lights, then a + 1's */
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < np; ++b) {
            size_t i = c0 + (size_t)a * np + b;
            gate_shade_theta(m + 9 * s->nlobes * i, magnitude + s->nlobes * i, s->nlobes,
                             a > 0 ? s->lights + GATE_NLIGHTS * (a - 1) : NULL,
                             a + 1 < nt ? s->lights + GATE_NLIGHTS * (a + 1) : NULL, X + 2 * GATE_MIRROR * (i - c0));
        }
    for (int a = 0; a < nt; ++a)
        for (int b = 0; b < np; ++b) {
            size_t i = c0 + (size_t)a * np + b, e = (size_t)grow * L->growlen + (size_t)L->gox * nv + i;
            if (!isfinite(A[i]))
                continue;
            double xs[2][GATE_NLIGHTS], ys[2][GATE_NLIGHTS], na[2];
            const double *xp[2], *yp[2], *rp[2];
            int dir[2], nn = 0;
            for (int q = 0; q < 2; ++q) {
                if (q ? a + 1 >= nt : a < 1)
                    continue;
                size_t j = q ? i + (size_t)np : i - (size_t)np;
                const double *Xi = X + 2 * GATE_MIRROR * (i - c0), *Xj = X + 2 * GATE_MIRROR * (j - c0);
                for (int k = 0; k < GATE_NLIGHTS; ++k) { /* the lights about the normal: every view's */
                    xs[nn][k] = k < GATE_MIRROR ? Xi[GATE_MIRROR * q + k] : S[GATE_NLIGHTS * i + k];
                    ys[nn][k] = k < GATE_MIRROR ? Xj[GATE_MIRROR * (1 - q) + k] : S[GATE_NLIGHTS * j + k];
                }
                xp[nn] = xs[nn], yp[nn] = ys[nn], rp[nn] = R + GATE_NLIGHTS * j, na[nn] = A[j], dir[nn] = q;
                ++nn;
            }
            mf_prefilter_gate_own o;
            mf_prefilter_gate_own_fit_cross(GATE_NLIGHTS, S + GATE_NLIGHTS * i, R + GATE_NLIGHTS * i, A[i], nn, xp, rp,
                                            yp, na, &o);
            if (o.owner_at >= 0)
                gs_worst(o.owner, &g->worst_cont_owner_theta, &s->k_cont_owner_theta, gs_key(li, e, 0, 0),
                         g->where_cont_owner_theta, sizeof g->where_cont_owner_theta, what[dir[o.owner_at]], L->level,
                         grow, gcol, a, b);
            if (o.dominated_at >= 0)
                gs_worst(o.dominated, &g->worst_cont_dominated_theta, &s->k_cont_dominated_theta, gs_key(li, e, 0, 0),
                         g->where_cont_dominated_theta, sizeof g->where_cont_dominated_theta, dwhat[dir[o.dominated_at]],
                         L->level, grow, gcol, a, b);
        }
}

/* The texel checks of row r of level index li (its rows r - 1 and r + 1, periodic for the
 * reference's, held), over the row's entries [i0, i1). */
static void gs_texel_checks(mf_prefilter_gate_stream *s, int li, int r, size_t i0, size_t i1)
{
    mf_prefilter_gate *g = s->g;
    const gs_level *L = &s->L[li];
    const int nt = s->nt, np = s->np, nv = s->nv;
    const double *S = L->S[gs_slot(r)], *R = L->R[gs_slot(r)];
    const float *A = L->A[gs_slot(r)];
    const int grow = L->goy + r; /* the row in the map's level */
    const int region = s->mode == 2 && li < s->nreg;
    if (region && s->whole)
        return; /* the one region tile checked every entry */
    for (size_t i = i0; i < i1; ++i) {
        int col = (int)(i / nv), a = (int)(i / np % nt), b = (int)(i % np), gcol = L->gox + col;
        /* a region tile checks its inner entries, rank 0 the tiles' borders (their neighbours in the
         * next tile) */
        if (s->mode == 1 && !s->whole && (r == 0 || r == L->h - 1 || col == 0 || col == L->w - 1))
            continue;
        if (region && gs_ring(L, r, col) != 1)
            continue;
        size_t e = (size_t)grow * L->growlen + (size_t)L->gox * nv + i;
        double alb = fmax(A[i], 1e-6);
        int gr = s->ref && cos(mf_prefilter_theta(&s->o, a)) < MF_PREFILTER_MULTISTART_COS;
        /* the texel neighbours along x and y (periodic: normal maps tile), once per entry: their S and
         * R (GATE_NLIGHTS each) and albedos; inner: not across the map's edge */
        const double *tS[2][2] = {{NULL, NULL}, {NULL, NULL}}, *tR[2][2] = {{NULL, NULL}, {NULL, NULL}};
        double ta0[2] = {0.0, 0.0}, ta1[2] = {0.0, 0.0};
        int has_t[2], inner[2];
        for (int ax = 0; ax < 2; ++ax) {
            has_t[ax] = (ax ? L->gh : L->gw) >= 2;
            inner[ax] = ax ? grow > 0 && grow + 1 < L->gh : gcol > 0 && gcol + 1 < L->gw;
            if (!has_t[ax])
                continue;
            int r1 = (r + (ax == 1)) % L->h, c1 = (col + (ax == 0)) % L->w;
            int r0 = (r - (ax == 1) + L->h) % L->h, c0 = (col - (ax == 0) + L->w) % L->w;
            size_t j1 = ((size_t)c1 * nt + a) * np + b, j0 = ((size_t)c0 * nt + a) * np + b;
            int s1 = gs_slot(r1), s0 = gs_slot(r0);
            tS[ax][0] = L->S[s0] + GATE_NLIGHTS * j0, tS[ax][1] = L->S[s1] + GATE_NLIGHTS * j1;
            if (s->ref)
                tR[ax][0] = L->R[s0] + GATE_NLIGHTS * j0, tR[ax][1] = L->R[s1] + GATE_NLIGHTS * j1;
            ta0[ax] = L->A[s0][j0], ta1[ax] = L->A[s1][j1];
        }
        /* the view neighbours: theta (interior rows), phi (periodic; rows theta > 0) */
        size_t vq[2][2] = {{i - np, i + np}, {i - b + (b + np - 1) % np, i - b + (b + 1) % np}};
        int has_v[2] = {a > 0 && a + 1 < nt, np >= 3 && a > 0};
        if (s->ref && isfinite(A[i]))
            gs_own_fit(s, li, grow, gcol, a, b, e, S + GATE_NLIGHTS * i, R + GATE_NLIGHTS * i, A[i], tS, tR, ta0, ta1,
                       has_t, vq[1], S, R, A);
        for (int k = 0; k < GATE_NLIGHTS; ++k) {
            double x = S[GATE_NLIGHTS * i + k];
            /* a lone texel above or below both neighbours along x or y (not periodic) */
            for (int ax = 0; ax < 2; ++ax) {
                if (!has_t[ax] || !inner[ax])
                    continue;
                double y0 = tS[ax][0][k], y1 = tS[ax][1][k];
                double up = fmin(x - y0, x - y1), dn = fmin(y0 - x, y1 - x);
                gs_worst(fmax(fmax(up, dn), 0.0) / alb, &g->worst_texel_spike, &s->k_texel, gs_key(li, e, k, 2 + ax),
                         g->where_texel, sizeof g->where_texel, "texel spike", L->level, grow, gcol, a, b);
            }
            if (!s->ref)
                continue;
            double rx = R[GATE_NLIGHTS * i + k], ex = x - rx;
            if (!isfinite(ex))
                continue; /* counted by the nan check */
            double te[2][2] = {{0.0, 0.0}, {0.0, 0.0}}; /* the texel neighbours' errors */
            for (int ax = 0; ax < 2; ++ax)
                if (has_t[ax])
                    te[ax][0] = tS[ax][0][k] - tR[ax][0][k], te[ax][1] = tS[ax][1][k] - tR[ax][1][k];
            /* cross: the error's lone extreme along every axis at once, the smallest of its lone
             * extremes along the axes the entry has (texels x, y; theta; phi), for the entries with a
             * texel axis; cross_texel: the same over the texel axes alone.  excess (gated): the same
             * over the axes, of the lobe's lone extreme beyond the reference's (gate_excess) */
            double lt = INFINITY, lv = INFINITY, xt = INFINITY, xv = INFINITY;
            for (int ax = 0; ax < 2; ++ax)
                if (has_t[ax]) {
                    lt = fmin(lt, gate_lone(ex, te[ax][0], te[ax][1]) / alb);
                    xt = fmin(xt, gate_excess(x, tS[ax][0][k], tS[ax][1][k], rx, tR[ax][0][k], tR[ax][1][k]) / alb);
                }
            for (int ax = 0; ax < 2; ++ax)
                if (has_v[ax]) {
                    double s0 = S[GATE_NLIGHTS * vq[ax][0] + k], s1 = S[GATE_NLIGHTS * vq[ax][1] + k];
                    double r0 = R[GATE_NLIGHTS * vq[ax][0] + k], r1 = R[GATE_NLIGHTS * vq[ax][1] + k];
                    lv = fmin(lv, gate_lone(ex, s0 - r0, s1 - r1) / alb);
                    xv = fmin(xv, gate_excess(x, s0, s1, rx, r0, r1) / alb);
                }
            if (isfinite(lt)) {
                gs_worst(fmin(xt, xv), &g->worst_cont_excess, &s->k_cont_excess, gs_key(li, e, k, 0),
                         g->where_cont_excess, sizeof g->where_cont_excess,
                         "lobe extreme beyond the reference's along every axis", L->level, grow, gcol, a, b);
                gs_worst(fmin(lt, lv), &g->worst_cont_cross, &s->k_cont_cross, gs_key(li, e, k, 0), g->where_cont_cross,
                         sizeof g->where_cont_cross, "error extreme along every axis", L->level, grow, gcol, a, b);
                gs_max(lt, &g->worst_cont_cross_texel);
            }
            /* the error's lone texel (periodic neighbours: normal maps tile) */
            for (int ax = 0; ax < 2; ++ax) {
                if (!has_t[ax])
                    continue;
                double ab = fmax(alb, ta1[ax]);
                gs_max(fabs(ex - te[ax][1]) / ab, &g->worst_jump_texel);
                gs_worst(gate_lone(ex, te[ax][0], te[ax][1]) / alb, gr ? &g->worst_cont_grazing : &g->worst_cont_texel,
                         gr ? &s->k_cont_grazing : &s->k_cont_texel, gs_key(li, e, k, 2 + ax),
                         gr ? g->where_cont_grazing : g->where_cont_texel, sizeof g->where_cont_texel,
                         "texel error spike", L->level, grow, gcol, a, b);
            }
        }
    }
}

/* The checks of row `row` of level index level_index that need no other row of its level, over its
 * columns [c0, c1): m, magnitude, albedo are the whole row's arrays. */
static void gs_row_cols(mf_prefilter_gate_stream *s, int level_index, int row, const float *m, const float *magnitude,
                        const float *albedo, const double *Rin, int c0, int c1)
{
    mf_prefilter_gate *g = s->g;
    const gs_level *L = &s->L[level_index];
    const int nt = s->nt, np = s->np, nv = s->nv, sl = gs_slot(row);
    double *S = L->S[sl], *R = L->R[sl];
    float *A = L->A[sl];
    const size_t i0 = (size_t)c0 * nv, i1 = (size_t)c1 * nv;
    const int grow = L->goy + row; /* the row in the map's level */
    /* rank 0 at a region level: the tiles ran these checks; it needs S of their two outer rings (the
     * texel checks of ring 1), of every entry at the top region level (the level check above) */
    const int region = s->mode == 2 && level_index < s->nreg, top = level_index == s->nreg - 1;
    /* energy, nan, the lobes' shading */
    for (size_t i = i0; i < i1; ++i) {
        int col = (int)(i / nv), a = (int)(i / np % nt), b = (int)(i % np), gcol = L->gox + col;
        size_t e = (size_t)grow * L->growlen + (size_t)L->gox * nv + i;
        const int nl = s->nlobes;
        const float *mi = m + 9 * nl * i, *mg = magnitude + nl * i;
        if (region) {
            A[i] = albedo ? albedo[i] : mg[0];
            if (top || (!s->whole && gs_ring(L, row, col)))
                gate_shade(mi, mg, nl, s->lights + GATE_NLIGHTS * a, S + GATE_NLIGHTS * i);
            continue;
        }
        float mag = mg[0];
        int bad = 0;
        for (int j = 0; j < nl; ++j)
            bad |= !isfinite(mg[j]) || !(mg[j] >= 0.0f);
        for (int q = 0; q < 9 * nl; ++q)
            bad |= !isfinite(mi[q]);
        A[i] = albedo ? albedo[i] : mag;
        if (!bad) {
            /* the lobe's albedo: magnitude * its mass above the horizon, (1 + n.z) / 2 with
             * n = M^T z / |M^T z| (the clamped cosine over the half-space (M^T z).w > 0); two lobes: the
             * sum of theirs against the entry's albedo */
            double la = 0.0;
            for (int j = 0; j < nl; ++j) {
                const float *mj = mi + 9 * j;
                double n2 = (double)mj[6] * mj[6] + (double)mj[7] * mj[7] + (double)mj[8] * mj[8];
                la += mg[j] * (0.5 * (1.0 + mj[8] / sqrt(n2)));
            }
            double alb = albedo ? albedo[i] : mag;
            gs_worst(alb > 0.0 ? fabs(la / alb - 1.0) : fabs(la), &g->worst_energy, &s->k_energy,
                     gs_key(level_index, e, 0, 0), g->where_energy, sizeof g->where_energy, "energy", L->level, grow,
                     gcol, a, b);
        }
        gate_shade(mi, mg, nl, s->lights + GATE_NLIGHTS * a, S + GATE_NLIGHTS * i);
        for (int k = 0; k < GATE_NLIGHTS; ++k)
            bad |= !isfinite(S[GATE_NLIGHTS * i + k]);
        g->nan_entries += bad;
    }
    /* the reference: given (the region tile's, read back: the same bits), or level 1 from its texels
     * and each level above as the mean of its children */
    if (s->ref && Rin) {
        memcpy(R + GATE_NLIGHTS * i0, Rin + GATE_NLIGHTS * i0, sizeof(double) * GATE_NLIGHTS * (i1 - i0));
    } else if (s->ref) {
        int cw = level_index ? s->L[level_index - 1].w : s->W, ch = level_index ? s->L[level_index - 1].h : s->H;
        const double *crow[2] = {NULL, NULL};
        for (int dy = 0; level_index && dy < 2; ++dy)
            if (2 * row + dy < ch)
                crow[dy] = s->L[level_index - 1].R[gs_slot(2 * row + dy)];
        gate_ref_cols(s->iso, s->clipped, &s->o, nt, np, level_index, row, c0, c1, s->normals, crow, cw, ch, R);
    }
    if (region)
        return;
    /* the checks within the row: views, levels; against the reference: the error, its jumps and
     * spikes along the views */
    for (size_t i = i0; i < i1; ++i) {
        int col = (int)(i / nv), a = (int)(i / np % nt), b = (int)(i % np), gcol = L->gox + col;
        size_t e = (size_t)grow * L->growlen + (size_t)L->gox * nv + i;
        double alb = fmax(A[i], 1e-6);
        int gr = s->ref && cos(mf_prefilter_theta(&s->o, a)) < MF_PREFILTER_MULTISTART_COS;
        size_t vm = i - b + (b + np - 1) % np, vp = i - b + (b + 1) % np; /* phi neighbours (periodic) */
        for (int k = 0; k < GATE_NLIGHTS; ++k) {
            double x = S[GATE_NLIGHTS * i + k];
            /* views: second differences along theta (interior) and phi (periodic) */
            if (a > 0 && a + 1 < nt) {
                double d = fabs(2.0 * x - S[GATE_NLIGHTS * (i - np) + k] - S[GATE_NLIGHTS * (i + np) + k]);
                gs_worst(0.5 * d / alb, &g->worst_view_spike, &s->k_view, gs_key(level_index, e, k, 0), g->where_view,
                         sizeof g->where_view, "theta spike", L->level, grow, gcol, a, b);
            }
            if (np >= 3 && a > 0) {
                double d = fabs(2.0 * x - S[GATE_NLIGHTS * vm + k] - S[GATE_NLIGHTS * vp + k]);
                gs_worst(0.5 * d / alb, &g->worst_view_spike, &s->k_view, gs_key(level_index, e, k, 1), g->where_view,
                         sizeof g->where_view, "phi spike", L->level, grow, gcol, a, b);
            }
            /* levels: the effective BRDF of a footprint is the mean of its four children's (equal
             * areas), so the parent's shading is compared with the mean of the children's */
            if (L->twice) {
                const gs_level *C = &s->L[level_index - 1];
                double mc = 0.0;
                for (int dy = 0; dy < 2; ++dy)
                    for (int dx = 0; dx < 2; ++dx)
                        mc += C->S[gs_slot(2 * row + dy)][GATE_NLIGHTS * ((((size_t)2 * col + dx) * nt + a) * np + b) + k];
                gs_worst(fabs(x - 0.25 * mc) / alb, &g->worst_level, &s->k_level, gs_key(level_index, e, k, 4),
                         g->where_level, sizeof g->where_level, "parent vs children", L->level, grow, gcol, a, b);
            }
            if (!s->ref)
                continue;
            double ex = x - R[GATE_NLIGHTS * i + k];
            if (!isfinite(ex))
                continue; /* counted by the nan check */
            gs_max(fabs(ex) / alb, &g->worst_ref_error);
            size_t vn[4] = {0};
            int has[4] = {a > 0, a + 1 < nt, np >= 3, np >= 2};
            if (has[0])
                vn[0] = i - np;
            if (has[1])
                vn[1] = i + np;
            vn[2] = vm, vn[3] = vp;
            double en[4] = {0.0};
            for (int q = 0; q < 4; ++q)
                en[q] = has[q] ? S[GATE_NLIGHTS * vn[q] + k] - R[GATE_NLIGHTS * vn[q] + k] : 0.0;
            for (int q = 0; q < 4; ++q)
                if (has[q] && (q != 3 || np >= 3 || b == 0))
                    gs_max(fabs(ex - en[q]) / fmax(alb, A[vn[q]]), &g->worst_jump_view);
            double *wv = gr ? &g->worst_cont_grazing : &g->worst_cont_view;
            uint64_t *kv = gr ? &s->k_cont_grazing : &s->k_cont_view;
            char *pv = gr ? g->where_cont_grazing : g->where_cont_view;
            if (has[0] && has[1])
                gs_worst(gate_lone(ex, en[0], en[1]) / alb, wv, kv, gs_key(level_index, e, k, 0), pv,
                         sizeof g->where_cont_view, "theta error spike", L->level, grow, gcol, a, b);
            if (np >= 3 && a > 0)
                gs_worst(gate_lone(ex, en[2], en[3]) / alb, wv, kv, gs_key(level_index, e, k, 1), pv,
                         sizeof g->where_cont_view, "phi error spike", L->level, grow, gcol, a, b);
        }
    }
    /* own fit across elevations: a column's views are all in this range */
    if (s->ref)
        for (int col = c0; col < c1; ++col)
            gs_own_fit_theta(s, level_index, row, col, m, magnitude, S, R, A);
}

/* ---- the streamed gate on threads ---------------------------------------------------------------
 * A row's entries are split into column ranges, one per thread: first the checks within the row
 * (gs_row_cols: a column's views read only that column), then, once the whole row is held, the
 * texel checks of the rows it completes (gs_texel_checks).  On one thread they run on the stream
 * itself, over the whole row.  On more, each part runs on a copy of the stream
 * whose gate results start cleared (worst 0, keys UINT64_MAX) and are merged into the stream's
 * afterwards with gs_worst's own rule (the larger value; on a tie, the smaller key) and max and sum
 * for the rest: that rule is a total order on the candidates, so the result, places included, does
 * not depend on the number of threads or on the split.  Every value is computed by the same code
 * from the same operands as on one thread. */
typedef struct gs_part {
    mf_prefilter_gate_stream loc; /* the stream, with loc.g = &res and its own keys */
    mf_prefilter_gate res;
    int task; /* 0: gs_row_cols; 1: gs_texel_checks of rows[0 .. nrows) */
    int li, row, nrows, rows[3], c0, c1;
    const float *m, *magnitude, *albedo;
    const double *Rin;
} gs_part;

static size_t gs_part_size(void) { return sizeof(gs_part); }

static void gs_part_init(gs_part *p, const mf_prefilter_gate_stream *s)
{
    memset(&p->res, 0, sizeof p->res); /* worsts 0, places "", nan_entries 0 */
    p->loc = *s;
    p->loc.g = &p->res;
    p->loc.k_energy = p->loc.k_level = p->loc.k_view = p->loc.k_texel = UINT64_MAX;
    p->loc.k_cont_texel = p->loc.k_cont_view = p->loc.k_cont_grazing = p->loc.k_cont_cross = UINT64_MAX;
    p->loc.k_cont_excess = p->loc.k_cont_owner = p->loc.k_cont_owner_view = UINT64_MAX;
    p->loc.k_cont_dominated = p->loc.k_cont_owner_theta = p->loc.k_cont_dominated_theta = UINT64_MAX;
}

static void *gs_part_run(void *arg)
{
    gs_part *p = arg;
    const size_t nv = (size_t)p->loc.nv;
    if (p->task == 0)
        gs_row_cols(&p->loc, p->li, p->row, p->m, p->magnitude, p->albedo, p->Rin, p->c0, p->c1);
    else
        for (int q = 0; q < p->nrows; ++q)
            gs_texel_checks(&p->loc, p->li, p->rows[q], (size_t)p->c0 * nv, (size_t)p->c1 * nv);
    return NULL;
}

static void gs_merge_worst(double v, uint64_t key, const char *where, double *worst, uint64_t *wkey, char *gwhere,
                           size_t n)
{
    if (v > *worst || (v == *worst && *worst > 0.0 && key < *wkey)) {
        *worst = v, *wkey = key;
        memset(gwhere, 0, n); /* as gs_worst */
        snprintf(gwhere, n, "%s", where);
    }
}

/* Merges a part's results into the stream's: every worst with its key and place, every gs_max
 * figure and the NaN count (a measure added to the gate must be added here too; one thread runs on
 * the stream itself, so test_prefilter_gate_threads sees a measure missing here as a difference
 * between 1 and 2 threads). */
static void gs_merge_res(mf_prefilter_gate_stream *s, const mf_prefilter_gate *r, const uint64_t *key);

static void gs_merge(mf_prefilter_gate_stream *s, const gs_part *p)
{
    const mf_prefilter_gate_stream *l = &p->loc;
    const uint64_t key[14] = {l->k_energy,     l->k_level,        l->k_view,       l->k_texel,
                              l->k_cont_texel, l->k_cont_view,    l->k_cont_grazing, l->k_cont_cross,
                              l->k_cont_excess, l->k_cont_owner, l->k_cont_owner_view, l->k_cont_dominated,
                              l->k_cont_owner_theta, l->k_cont_dominated_theta};
    gs_merge_res(s, &p->res, key);
}

/* Merges results r with the keys of their worsts (in mf_prefilter_gate_part's order) into the stream's. */
static void gs_merge_res(mf_prefilter_gate_stream *s, const mf_prefilter_gate *r, const uint64_t *key)
{
    mf_prefilter_gate *g = s->g;
#define GS_MERGE(field, q, skey, where) gs_merge_worst(r->field, key[q], r->where, &g->field, &s->skey, g->where, sizeof g->where)
    GS_MERGE(worst_energy, 0, k_energy, where_energy);
    GS_MERGE(worst_level, 1, k_level, where_level);
    GS_MERGE(worst_view_spike, 2, k_view, where_view);
    GS_MERGE(worst_texel_spike, 3, k_texel, where_texel);
    GS_MERGE(worst_cont_texel, 4, k_cont_texel, where_cont_texel);
    GS_MERGE(worst_cont_view, 5, k_cont_view, where_cont_view);
    GS_MERGE(worst_cont_grazing, 6, k_cont_grazing, where_cont_grazing);
    GS_MERGE(worst_cont_cross, 7, k_cont_cross, where_cont_cross);
    GS_MERGE(worst_cont_excess, 8, k_cont_excess, where_cont_excess);
    GS_MERGE(worst_cont_owner, 9, k_cont_owner, where_cont_owner);
    GS_MERGE(worst_cont_owner_view, 10, k_cont_owner_view, where_cont_owner_view);
    GS_MERGE(worst_cont_dominated, 11, k_cont_dominated, where_cont_dominated);
    GS_MERGE(worst_cont_owner_theta, 12, k_cont_owner_theta, where_cont_owner_theta);
    GS_MERGE(worst_cont_dominated_theta, 13, k_cont_dominated_theta, where_cont_dominated_theta);
#undef GS_MERGE
    gs_max(r->worst_jump_texel, &g->worst_jump_texel);
    gs_max(r->worst_jump_view, &g->worst_jump_view);
    gs_max(r->worst_ref_error, &g->worst_ref_error);
    gs_max(r->worst_cont_cross_texel, &g->worst_cont_cross_texel);
    g->nan_entries += r->nan_entries;
}

/* Runs parts[0 .. n) (parts 1.. on their own threads, part 0 here; a part whose thread cannot start
 * runs here too), then merges them in order. */
static void gs_parts_run(mf_prefilter_gate_stream *s, gs_part *parts, int n)
{
    pthread_t tid[GS_MAX_THREADS];
    int started[GS_MAX_THREADS] = {0};
    for (int t = 1; t < n; ++t)
        started[t] = pthread_create(&tid[t], NULL, gs_part_run, &parts[t]) == 0;
    gs_part_run(&parts[0]);
    for (int t = 1; t < n; ++t) {
        if (started[t])
            pthread_join(tid[t], NULL);
        else
            gs_part_run(&parts[t]);
    }
    for (int t = 0; t < n; ++t)
        gs_merge(s, &parts[t]);
}

/* Splits task (0: gs_row_cols of row; 1: gs_texel_checks of rows[0 .. nrows)) of level index li into
 * n column ranges and runs them (gs_parts_run). */
static void gs_split(mf_prefilter_gate_stream *s, int n, int task, int li, int row, const float *m,
                     const float *magnitude, const float *albedo, const double *Rin, const int *rows, int nrows)
{
    const int w = s->L[li].w;
    for (int t = 0; t < n; ++t) {
        gs_part *p = &s->parts[t];
        gs_part_init(p, s);
        p->task = task, p->li = li, p->row = row, p->nrows = nrows;
        p->m = m, p->magnitude = magnitude, p->albedo = albedo, p->Rin = Rin;
        for (int q = 0; q < nrows; ++q)
            p->rows[q] = rows[q];
        p->c0 = (int)((long)w * t / n), p->c1 = (int)((long)w * (t + 1) / n);
        if (s->xscr_all) /* the part's own scratch (its copy of the stream shares the pointers) */
            p->loc.xscr = s->xscr_all + 2 * GATE_MIRROR * (size_t)s->nv * t;
    }
    gs_parts_run(s, s->parts, n);
}

mf_status mf_prefilter_gate_stream_set_lobes(mf_prefilter_gate_stream *s, int nlobes)
{
    if (!s || nlobes < 1 || nlobes > 2 || s->half || s->mode != 0)
        return MF_ERR_DOMAIN;
    for (int l = 0; l < s->nl; ++l)
        if (s->L[l].fed)
            return MF_ERR_DOMAIN;
    s->nlobes = nlobes;
    return MF_OK;
}

mf_status mf_prefilter_gate_stream_row(mf_prefilter_gate_stream *s, int level_index, int row, const float *m,
                                       const float *magnitude, const float *albedo)
{
    return mf_prefilter_gate_stream_row_ref(s, level_index, row, m, magnitude, albedo, NULL);
}

mf_status mf_prefilter_gate_stream_row_ref(mf_prefilter_gate_stream *s, int level_index, int row, const float *m,
                                           const float *magnitude, const float *albedo, const double *ref)
{
    int want_l, want_r;
    if (!s || !m || !magnitude || !mf_prefilter_gate_stream_next(s, &want_l, &want_r) || level_index != want_l ||
        row != want_r)
        return MF_ERR_DOMAIN;
    if (s->ref && !ref && (s->mode == 1 || (s->mode == 2 && level_index < s->nreg)))
        return MF_ERR_DOMAIN; /* the region levels' R comes with their rows */
    if (s->nlobes > 1 && !albedo)
        return MF_ERR_DOMAIN; /* two lobes: the entries' albedos come with their rows */
    gs_level *L = &s->L[level_index];
    /* one part per thread, at least one column each; one thread works on the stream itself */
    const int n = s->threads < L->w ? s->threads : L->w;
    if (n == 1)
        gs_row_cols(s, level_index, row, m, magnitude, albedo, ref, 0, L->w);
    else
        gs_split(s, n, 0, level_index, row, m, magnitude, albedo, ref, NULL, 0);
    L->fed++;
    /* the texel checks of the row above (its neighbours now held); at the level's end, the last row
     * and row 0 (periodic neighbours) */
    int rows[3], nrows = 0;
    if (row >= 2)
        rows[nrows++] = row - 1;
    if (row == L->h - 1) {
        if (row >= 1)
            rows[nrows++] = row;
        rows[nrows++] = 0;
    }
    if (n == 1)
        for (int q = 0; q < nrows; ++q)
            gs_texel_checks(s, level_index, rows[q], 0, L->rowlen);
    else if (nrows)
        gs_split(s, n, 1, level_index, row, NULL, NULL, NULL, NULL, rows, nrows);
    return MF_OK;
}

mf_status mf_prefilter_gate_stream_end(mf_prefilter_gate_stream *s)
{
    if (!s)
        return MF_ERR_DOMAIN;
    int l, r;
    if (mf_prefilter_gate_stream_next(s, &l, &r)) {
        mf_prefilter_gate_stream_free(s);
        return MF_ERR_DOMAIN; /* rows not fed */
    }
    mf_prefilter_gate *g = s->g;
    g->pass_energy = g->worst_energy <= g->max_energy;
    g->pass_nan = g->nan_entries == 0;
    g->pass_level = g->worst_level <= g->max_level;
    g->pass_view = g->worst_view_spike <= g->max_view_spike;
    g->pass_texel = g->worst_texel_spike <= g->max_texel_spike;
    /* the view and texel spikes are reported, not gated: a coarse view grid and a sharp map give
     * genuine spikes (the V-groove's level-1 texels alternate between two tilts) */
    g->pass = g->pass_energy && g->pass_nan && g->pass_level;
    if (s->ref) {
        /* GGX: reported, not gated (they do not separate good from corrupted runs); Lambert: gated
         * (mf_prefilter.h) */
        g->cont_gated = s->lambert;
        g->pass_cont_texel = g->worst_cont_texel <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_texel);
        g->pass_cont_view = g->worst_cont_view <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_view);
        g->pass_cont_grazing = g->worst_cont_grazing <= (g->cont_gated ? g->max_cont_lambert : g->max_cont_grazing);
        g->pass_cont_cross = g->worst_cont_cross <= g->max_cont_cross;
        if (g->cont_gated)
            g->pass = g->pass && g->pass_cont_texel && g->pass_cont_view && g->pass_cont_grazing;
        /* excess: gated for both tables (docs/prefilter.md, "Gating continuity across texels") */
        g->pass_cont_excess = g->worst_cont_excess <= g->max_cont_excess;
        g->pass = g->pass && g->pass_cont_excess;
        /* own fit, texel and azimuth neighbours: gated for both tables (docs/prefilter.md, "Gating copied
         * lobes (own fit)") */
        g->pass_cont_owner = g->worst_cont_owner <= g->max_cont_owner && g->worst_cont_owner_view <= g->max_cont_owner;
        g->pass = g->pass && g->pass_cont_owner;
        /* own fit across elevations (docs/prefilter.md, "Own fit across elevations") */
        g->pass_cont_owner_theta = g->worst_cont_owner_theta <= g->max_cont_owner_theta;
        g->owner_theta_gated = MF_PREFILTER_GATE_OWN_FIT_THETA_GATED;
        if (g->owner_theta_gated)
            g->pass = g->pass && g->pass_cont_owner_theta;
    }
    g->half_table = s->half;
    if (s->half)
        g->pass = g->pass_energy && g->pass_nan;
    mf_prefilter_gate_stream_free(s);
    return MF_OK;
}

/* The whole-level entry points: every row of levels held in memory, fed in the stream's order. */
static mf_status gate_levels(const mf_prefilter_level *levels, int nlevels, const double *normals, int width,
                             int height, const mf_prefilter_options *o, mf_prefilter_gate *g)
{
    mf_prefilter_gate_stream *s;
    mf_status st = mf_prefilter_gate_stream_begin(levels, nlevels, normals, width, height, o, g, &s);
    if (st != MF_OK)
        return st;
    int l, r;
    while (st == MF_OK && mf_prefilter_gate_stream_next(s, &l, &r)) {
        const mf_prefilter_level *lv = &levels[l];
        size_t off = (size_t)r * lv->width * lv->n_theta * lv->n_phi;
        if (!lv->m || !lv->magnitude)
            st = MF_ERR_DOMAIN;
        else
            st = mf_prefilter_gate_stream_row(s, l, r, lv->m + 9 * off, lv->magnitude + off,
                                              lv->albedo ? lv->albedo + off : NULL);
    }
    if (st != MF_OK) {
        mf_prefilter_gate_stream_free(s);
        return st;
    }
    return mf_prefilter_gate_stream_end(s);
}

mf_status mf_prefilter_gate_run(const mf_prefilter_level *levels, int nlevels, mf_prefilter_gate *g)
{
    return gate_levels(levels, nlevels, NULL, 0, 0, NULL, g);
}

mf_status mf_prefilter_gate_run_ref(const mf_prefilter_level *levels, int nlevels, const double *normals, int width,
                                    int height, const mf_prefilter_options *o, mf_prefilter_gate *g)
{
    if (!levels || nlevels < 1 || !g || !normals || !o || width < 1 || height < 1)
        return MF_ERR_DOMAIN;
    return gate_levels(levels, nlevels, normals, width, height, o, g);
}

void mf_prefilter_gate_pair_row(const float *ma, const float *ga, const float *aa, const float *mb, const float *gb,
                                const float *ab, size_t n, float *m, float *mag, float *alb)
{
    for (size_t i = 0; i < n; ++i) {
        memcpy(m + 18 * i, ma + 9 * i, sizeof(float) * 9);
        memcpy(m + 18 * i + 9, mb + 9 * i, sizeof(float) * 9);
        mag[2 * i] = ga[i], mag[2 * i + 1] = gb[i];
        alb[i] = (float)((double)aa[i] + (double)ab[i]);
    }
}

mf_status mf_prefilter_gate_run_pair(const mf_prefilter_level *la, const mf_prefilter_level *lb, int nlevels,
                                     const double *normals, int width, int height, const mf_prefilter_options *o,
                                     mf_prefilter_gate *g)
{
    if (!la || !lb || nlevels < 1 || !g || !normals || !o || o->lobe != 0 || width < 1 || height < 1)
        return MF_ERR_DOMAIN;
    for (int l = 0; l < nlevels; ++l)
        if (la[l].width != lb[l].width || la[l].height != lb[l].height || la[l].n_theta != lb[l].n_theta ||
            la[l].n_phi != lb[l].n_phi || !la[l].m || !lb[l].m || !la[l].magnitude || !lb[l].magnitude ||
            !la[l].albedo || !lb[l].albedo)
            return MF_ERR_DOMAIN;
    mf_prefilter_gate_stream *s;
    mf_status st = mf_prefilter_gate_stream_begin(la, nlevels, normals, width, height, o, g, &s);
    if (st != MF_OK)
        return st;
    st = mf_prefilter_gate_stream_set_lobes(s, 2);
    size_t most = 0;
    for (int l = 0; l < nlevels; ++l)
        most = (size_t)la[l].width * la[l].n_theta * la[l].n_phi > most ? (size_t)la[l].width * la[l].n_theta * la[l].n_phi : most;
    float *m = malloc(sizeof(float) * 18 * most), *mag = malloc(sizeof(float) * 2 * most), *alb = malloc(sizeof(float) * most);
    if (st == MF_OK && (!m || !mag || !alb))
        st = MF_ERR_ALLOC;
    int l, r;
    while (st == MF_OK && mf_prefilter_gate_stream_next(s, &l, &r)) {
        size_t n = (size_t)la[l].width * la[l].n_theta * la[l].n_phi, off = (size_t)r * n;
        mf_prefilter_gate_pair_row(la[l].m + 9 * off, la[l].magnitude + off, la[l].albedo + off, lb[l].m + 9 * off,
                                   lb[l].magnitude + off, lb[l].albedo + off, n, m, mag, alb);
        st = mf_prefilter_gate_stream_row(s, l, r, m, mag, alb);
    }
    free(m), free(mag), free(alb);
    if (st != MF_OK) {
        mf_prefilter_gate_stream_free(s);
        return st;
    }
    return mf_prefilter_gate_stream_end(s);
}

/* ---- the reference of a region tile, computed where the tile is fitted ------------------------ */

typedef struct {
    const gate_iso *iso;
    const gate_clipped *clipped;
    const mf_prefilter_options *o;
    const double *normals;
    int nt, np, width, height, w1, r0, r1;
    double *R1;
} gr_part;

static void *gr_part_run(void *arg) /* level 1's rows [r0, r1): each row from its own texels */
{
    const gr_part *p = arg;
    const double *const none[2] = {NULL, NULL};
    for (int row = p->r0; row < p->r1; ++row)
        gate_ref_cols(p->iso, p->clipped, p->o, p->nt, p->np, 0, row, 0, p->w1, p->normals, none, p->width, p->height,
                      p->R1 + GATE_NLIGHTS * (size_t)row * p->w1 * p->nt * p->np);
    return NULL;
}

mf_status mf_prefilter_gate_reference(const mf_prefilter_level *shapes, int nlevels, const double *normals, int width,
                                      int height, const mf_prefilter_options *o, double *const *R)
{
    if (!shapes || nlevels < 1 || nlevels > 64 || !normals || !o || width < 1 || height < 1 || !R)
        return MF_ERR_DOMAIN;
    const int nt = o->n_theta, np = o->n_phi;
    if (nt < 2 || np < 1)
        return MF_ERR_DOMAIN;
    for (int l = 0; l < nlevels; ++l) {
        int k = l + 1, w = width >> k, h = height >> k;
        if (!R[l] || shapes[l].level != k || shapes[l].width != (w > 0 ? w : 1) || shapes[l].height != (h > 0 ? h : 1) ||
            shapes[l].n_theta != nt || shapes[l].n_phi != np)
            return MF_ERR_DOMAIN;
    }
    mf_polygon *lights = malloc(sizeof *lights * GATE_NLIGHTS * (size_t)nt);
    gate_clipped *clipped = malloc(sizeof *clipped * GATE_NLIGHTS * (size_t)nt);
    gate_iso *iso = malloc(sizeof *iso);
    mf_status st = lights && clipped && iso ? MF_OK : MF_ERR_ALLOC;
    for (int a = 0; st == MF_OK && a < nt; ++a) /* as mf_prefilter_gate_stream_begin */
        gate_lights(a / (double)(nt - 1) * MF_PREFILTER_THETA_MAX, lights + GATE_NLIGHTS * a);
    for (int q = 0; st == MF_OK && q < GATE_NLIGHTS * nt; ++q)
        clipped[q].n = clip_upper(&lights[q], clipped[q].v);
    if (st == MF_OK)
        st = gate_iso_fit(o, iso);
    if (st == MF_OK) {
        /* level 1 (nearly all the work: 4 texels x GATE_NLIGHTS polygon integrals per entry), its rows
         * split over o->threads (each row is computed by the same code whatever thread runs it) */
        const int h1 = shapes[0].height;
        int n = o->threads > 1 ? (o->threads < GS_MAX_THREADS ? o->threads : GS_MAX_THREADS) : 1;
        n = n < h1 ? n : h1;
        gr_part parts[GS_MAX_THREADS];
        pthread_t tid[GS_MAX_THREADS];
        int started[GS_MAX_THREADS] = {0};
        for (int t = 0; t < n; ++t)
            parts[t] = (gr_part){iso, clipped, o, normals, nt, np, width, height, shapes[0].width,
                                 (int)((long)h1 * t / n), (int)((long)h1 * (t + 1) / n), R[0]};
        for (int t = 1; t < n; ++t)
            started[t] = pthread_create(&tid[t], NULL, gr_part_run, &parts[t]) == 0;
        gr_part_run(&parts[0]);
        for (int t = 1; t < n; ++t) {
            if (started[t])
                pthread_join(tid[t], NULL);
            else
                gr_part_run(&parts[t]);
        }
        /* the levels above: the mean of their children */
        for (int l = 1; l < nlevels; ++l) {
            const mf_prefilter_level *C = &shapes[l - 1];
            const size_t crl = GATE_NLIGHTS * (size_t)C->width * nt * np, rl = GATE_NLIGHTS * (size_t)shapes[l].width * nt * np;
            for (int row = 0; row < shapes[l].height; ++row) {
                const double *crow[2] = {NULL, NULL};
                for (int dy = 0; dy < 2; ++dy)
                    if (2 * row + dy < C->height)
                        crow[dy] = R[l - 1] + crl * (size_t)(2 * row + dy);
                gate_ref_cols(iso, clipped, o, nt, np, l, row, 0, shapes[l].width, normals, crow, C->width, C->height,
                              R[l] + rl * (size_t)row);
            }
        }
    }
    free(lights), free(clipped), free(iso);
    return st;
}

/* ---- the gate across tiles: a region tile's part, rank 0's merge -------------------------------- */

mf_status mf_prefilter_gate_stream_merge(mf_prefilter_gate_stream *s, const mf_prefilter_gate_part *p)
{
    if (!s || !p || s->mode != 2)
        return MF_ERR_DOMAIN;
    gs_merge_res(s, &p->res, p->keys);
    return MF_OK;
}

mf_status mf_prefilter_gate_region(const mf_prefilter_level *levels, int nlevels, double *const *R, int map_w,
                                   int map_h, int x0, int y0, int rw, int rh, const mf_prefilter_options *o,
                                   mf_prefilter_gate_part *part)
{
    if (!levels || !R || !o || !part || rw < 1 || rh < 1 || map_w < rw || map_h < rh || map_w % rw || map_h % rh ||
        x0 < 0 || y0 < 0 || x0 % rw || y0 % rh || x0 >= map_w || y0 >= map_h)
        return MF_ERR_DOMAIN;
    for (int l = 0; l < nlevels; ++l)
        if (!R[l] || !levels[l].m || !levels[l].magnitude)
            return MF_ERR_DOMAIN;
    memset(part, 0, sizeof *part);
    mf_prefilter_gate_bounds_default(&part->res);
    mf_prefilter_gate_stream *s;
    mf_status st = gs_begin(levels, nlevels, NULL, 1, 0, rw, rh, o, &part->res, &s);
    if (st != MF_OK)
        return st;
    s->mode = 1, s->whole = rw == map_w && rh == map_h;
    for (int l = 0; l < nlevels; ++l) { /* the map's level and the tile's place in it */
        gs_level *L = &s->L[l];
        int k = l + 1;
        L->gw = map_w >> k > 0 ? map_w >> k : 1, L->gh = map_h >> k > 0 ? map_h >> k : 1;
        L->gox = x0 / rw * L->w, L->goy = y0 / rh * L->h;
        L->growlen = (size_t)L->gw * s->nv;
        if (L->gox + L->w > L->gw || L->goy + L->h > L->gh) {
            mf_prefilter_gate_stream_free(s);
            return MF_ERR_DOMAIN;
        }
    }
    int l, r;
    while (st == MF_OK && mf_prefilter_gate_stream_next(s, &l, &r)) {
        const mf_prefilter_level *lv = &levels[l];
        size_t off = (size_t)r * lv->width * lv->n_theta * lv->n_phi;
        st = mf_prefilter_gate_stream_row_ref(s, l, r, lv->m + 9 * off, lv->magnitude + off,
                                              lv->albedo ? lv->albedo + off : NULL, R[l] + GATE_NLIGHTS * off);
    }
    if (st == MF_OK) {
        const uint64_t key[14] = {s->k_energy,       s->k_level,      s->k_view,          s->k_texel,
                                  s->k_cont_texel,   s->k_cont_view,  s->k_cont_grazing,  s->k_cont_cross,
                                  s->k_cont_excess,  s->k_cont_owner, s->k_cont_owner_view, s->k_cont_dominated,
                                  s->k_cont_owner_theta, s->k_cont_dominated_theta};
        memcpy(part->keys, key, sizeof key);
    }
    mf_prefilter_gate_stream_free(s);
    return st;
}
