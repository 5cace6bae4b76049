/* test_prefilter_gate_files.c -- the prefilter gate (mf_prefilter_gate_run_ref) run again on a table
 * `mfkit prefilter` wrote: its levels read back from DIR/ltc_mip<k>.npy, magnitude_mip<k>.npy and
 * albedo_mip<k>.npy, the normals decoded from the map as the command decodes them (unorm PNG, green
 * up, renormalised), the options (base, roughness, views) from the arguments.  A measuring tool for
 * docs/prefilter_log.md ("Gating continuity across texels"), not a CTest test: it prints every
 * figure of the gate's result.
 *
 * Usage: test_prefilter_gate_files DIR MAP NT NP [ggx|lambert] [ALPHA] [THREADS] [corrupt NCORR [SEED [KINDS]]]
 *   corrupt: then NCORR corruptions of each kind in KINDS (digits, default 0123: the draws of the
 *   first measurements), one at a time on the good table, each gated and
 *   printed on one line: kind, level, the shading change (lobe_change), the gated checks' verdict and
 *   the continuity measures.  Kinds: 0 one matrix entry (among those >= 0.05 of the largest) scaled by
 *   1 + s, s log-uniform in [0.02, 1]; 1 the lobe swapped with its phi neighbour; 2 the lobe mirrored
 *   (x -> -x: its highlight on the other side of the view plane); 3 the lobe replaced by its texel
 *   neighbour's (x + 1, periodic) at the same view; then, each magnitude scaled to keep the entry's
 *   albedo (so the energy check cannot see the move): 4 the lobe swapped with its texel neighbour
 *   x + 1; 5 copied from texel y + 1; 6 copied from its phi neighbour b + 1; 7 copied from its theta
 *   neighbour (a + 1, a - 1 on the last row); 8 swapped with it; 9 a run of 4 texels along x (fewer on
 *   narrow levels), every view, each given its x + 1 neighbour's lobes (a tile written one texel off);
 *   a (10) a run of 4 texels along x (fewer on narrow levels), every view given its theta neighbour's
 *   lobe (a + 1, a - 1 on the last row; magnitudes kept per albedo): a table written one elevation off.
 *   Levels drawn uniformly, except a 1 x 1 top level (no texel neighbours: the continuity measures do
 *   not cover it).  Each line also prints own fit across elevations (ownert, dominatedt). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mfkit/fit/mf_image_oiio.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_polygon.h"

#include "mf_test_prefilter_gate.h"

/* reads a little-endian float32 C-order .npy of n values (its shape not checked beyond the count) */
static float *read_npy(const char *path, size_t n)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char h[10];
    float *v = NULL;
    if (fread(h, 1, 10, f) == 10 && !memcmp(h, "\x93NUMPY", 6)) {
        size_t hl = h[6] == 1 ? (size_t)(h[8] | h[9] << 8) : 0;
        if (h[6] != 1) {
            unsigned char e[2];
            if (fread(e, 1, 2, f) == 2)
                hl = (size_t)h[8] | (size_t)h[9] << 8 | (size_t)e[0] << 16 | (size_t)e[1] << 24;
        }
        char *hdr = malloc(hl + 1);
        if (hdr && fread(hdr, 1, hl, f) == hl) {
            hdr[hl] = 0;
            if (strstr(hdr, "'<f4'")) {
                v = malloc(sizeof(float) * n);
                if (v && fread(v, sizeof(float), n, f) != n)
                    free(v), v = NULL;
            }
        }
        free(hdr);
    }
    fclose(f);
    return v;
}

/* moves lobe f's matrix into entry e, its magnitude scaled so that the lobe keeps e's albedo (the
 * energy check then cannot see the move; src holds f's saved matrix and magnitude) */
static void put_lobe(mf_prefilter_level *L, size_t e, size_t f, const float *src)
{
    memcpy(L->m + 9 * e, src, 36);
    L->magnitude[e] = L->albedo[e] / L->albedo[f] * src[9];
}

static void corrupt(mf_prefilter_level *lv, int nl, const double *n, int W, int H, const mf_prefilter_options *o,
                    int ncorr, uint64_t seed, const char *kinds)
{
    const int nt = o->n_theta, np = o->n_phi, nk = (int)strlen(kinds);
    size_t nv = (size_t)nt * np;
    size_t *idx = malloc(sizeof(size_t) * 4 * nv);
    float *sv = malloc(sizeof(float) * 10 * 4 * nv);
    for (int c = 0; c < nk * ncorr; ++c) {
        int kind = kinds[c % nk] >= 'a' ? kinds[c % nk] - 'a' + 10 : kinds[c % nk] - '0';
        int nlt = nl - (lv[nl - 1].width == 1 && lv[nl - 1].height == 1 && nl > 1); /* not the 1 x 1 top level: no texel axis */
        int l = (int)(lcg(&seed) % (uint64_t)nlt);
        mf_prefilter_level *L = &lv[l];
        size_t ne = (size_t)L->width * L->height * nv;
        size_t e = lcg(&seed) % ne, f = e;
        int b = (int)(e % (size_t)np), a = (int)(e / (size_t)np % (size_t)nt);
        double s = 0.02 * pow(50.0, (double)lcg(&seed) / 2147483648.0);
        size_t t = e / nv, row = t / (size_t)L->width, col = t % (size_t)L->width;
        size_t tx = (row * (size_t)L->width + (col + 1) % (size_t)L->width) * nv + e % nv; /* x + 1, same view */
        size_t ty = (((row + 1) % (size_t)L->height) * (size_t)L->width + col) * nv + e % nv; /* y + 1 */
        size_t vphi = e - b + (size_t)((b + 1) % np), vth = a + 1 < nt ? e + np : e - np;
        int nch = 0; /* the changed entries, saved in idx, sv */
        if (kind == 1 || kind == 4 || kind == 8)
            f = kind == 1 ? vphi : kind == 4 ? tx : vth;
        if (kind == 10) { /* a run of up to 4 texels along x, every view given its theta neighbour's lobe (a + 1;
                             a - 1 on the last row): a table written one elevation off */
            int run = L->width >= 4 ? 4 : L->width;
            for (int q = 0; q < run; ++q)
                for (size_t v = 0; v < nv; ++v) {
                    size_t x = (row * (size_t)L->width + (col + q) % (size_t)L->width) * nv + v;
                    idx[nch] = x, memcpy(sv + 10 * nch, L->m + 9 * x, 36), sv[10 * nch + 9] = L->magnitude[x], ++nch;
                }
            for (int q = 0; q < nch; ++q) { /* from the saved lobes: every source is changed too */
                int aq = (int)(q % nv / (size_t)np);
                int src = aq + 1 < nt ? q + np : q - np;
                put_lobe(L, idx[q], idx[src], sv + 10 * src);
            }
        } else if (kind == 9) { /* a run of up to 4 texels along x, every view, each given its x + 1 neighbour's lobes */
            int run = L->width >= 5 ? 4 : L->width - 1;
            for (int q = 0; q < run; ++q)
                for (size_t v = 0; v < nv; ++v) {
                    size_t x = (row * (size_t)L->width + (col + q) % (size_t)L->width) * nv + v;
                    idx[nch] = x, memcpy(sv + 10 * nch, L->m + 9 * x, 36), sv[10 * nch + 9] = L->magnitude[x], ++nch;
                }
            for (int q = 0; q < nch; ++q) { /* in order: x + 1 of the last one is not yet changed */
                size_t x = idx[q], src = ((row * (size_t)L->width + (col + q / nv + 1) % (size_t)L->width) * nv) + x % nv;
                float cur[10];
                memcpy(cur, L->m + 9 * src, 36), cur[9] = L->magnitude[src];
                put_lobe(L, x, src, cur);
            }
        } else {
            idx[nch] = e, memcpy(sv, L->m + 9 * e, 36), sv[9] = L->magnitude[e], ++nch;
            if (f != e)
                idx[nch] = f, memcpy(sv + 10, L->m + 9 * f, 36), sv[19] = L->magnitude[f], ++nch;
        }
        float *se = sv, *sf = sv + 10;
        if (kind == 3) { /* texel neighbour x + 1 (periodic) at the same view */
            memcpy(L->m + 9 * e, L->m + 9 * tx, 36), L->magnitude[e] = L->albedo[e] / L->albedo[tx] * L->magnitude[tx];
        } else if (kind == 5 || kind == 6 || kind == 7) { /* copied: texel y + 1, azimuth b + 1, elevation a +- 1 */
            size_t src = kind == 5 ? ty : kind == 6 ? vphi : vth;
            float cur[10];
            memcpy(cur, L->m + 9 * src, 36), cur[9] = L->magnitude[src];
            put_lobe(L, e, src, cur);
        } else if (kind == 4 || kind == 8) { /* swapped: texel x + 1, elevation a +- 1 (magnitudes kept per albedo) */
            put_lobe(L, e, f, sf), put_lobe(L, f, e, se);
        } else if (kind == 2) {
            float *m = L->m + 9 * e;
            m[1] = -m[1], m[2] = -m[2], m[3] = -m[3], m[6] = -m[6];
        } else if (kind == 1) {
            memcpy(L->m + 9 * e, sf, 36), L->magnitude[e] = sf[9];
            memcpy(L->m + 9 * f, se, 36), L->magnitude[f] = se[9];
        } else if (kind == 0) {
            float big = 0.0f;
            for (int i = 0; i < 9; ++i)
                big = fmaxf(big, fabsf(se[i]));
            int cand[9], nc = 0;
            for (int i = 0; i < 9; ++i)
                if (fabsf(se[i]) >= 0.05f * big)
                    cand[nc++] = i;
            int i = cand[lcg(&seed) % (uint64_t)nc];
            L->m[9 * e + i] = (float)(se[i] * (1.0 + s));
        }
        double ch = 0.0;
        for (int q = 0; q < nch; ++q)
            ch = fmax(ch, lobe_change(L, idx[q], sv + 10 * q, o));
        mf_prefilter_gate g;
        mf_prefilter_gate_bounds_default(&g);
        if (mf_prefilter_gate_run_ref(lv, nl, n, W, H, o, &g) != MF_OK)
            exit(1);
        printf("C kind %d level %d texel %zu %zu view %d %d change %.5f gated %d cross %.5f excess %.5f "
               "cont %.5f %.5f %.5f owner %.5f ownerv %.5f dominated %.5f ownert %.5f dominatedt %.5f pass %d\n", kind,
               L->level, col, row, a, b, ch,
               !(g.pass_energy && g.pass_nan && g.pass_level), g.worst_cont_cross, g.worst_cont_excess,
               g.worst_cont_texel, g.worst_cont_view, g.worst_cont_grazing, g.worst_cont_owner, g.worst_cont_owner_view,
               g.worst_cont_dominated, g.worst_cont_owner_theta, g.worst_cont_dominated_theta, g.pass);
        fflush(stdout);
        for (int q = nch - 1; q >= 0; --q)
            memcpy(L->m + 9 * idx[q], sv + 10 * q, 36), L->magnitude[idx[q]] = sv[10 * q + 9];
    }
    free(idx), free(sv);
}

int main(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: test_prefilter_gate_files DIR MAP NT NP [ggx|lambert] [ALPHA] [THREADS]\n");
        return 2;
    }
    const char *dir = argv[1], *map = argv[2];
    mf_prefilter_options o;
    int lambert = argc > 5 && !strcmp(argv[5], "lambert");
    if (lambert)
        mf_prefilter_options_default_diffuse(&o);
    else
        mf_prefilter_options_default(&o);
    o.n_theta = atoi(argv[3]), o.n_phi = atoi(argv[4]);
    if (argc > 6)
        o.alpha = atof(argv[6]);
    if (argc > 7)
        o.threads = atoi(argv[7]);
    mf_image_set_backend(mf_image_oiio_backend());
    mf_image img;
    char msg[512];
    if (mf_image_read_ex(map, &img, NULL, NULL, msg, sizeof msg) != MF_OK || img.channels < 3) {
        fprintf(stderr, "%s: cannot read (%s)\n", map, msg);
        return 2;
    }
    const int W = img.width, H = img.height;
    double *n = malloc(sizeof(double) * 3 * (size_t)W * H);
    for (size_t t = 0; t < (size_t)W * H; ++t) {
        double v[3], l = 0.0;
        for (int c = 0; c < 3; ++c)
            v[c] = 2.0 * (double)img.pixels[t * img.channels + c] - 1.0, l += v[c] * v[c];
        l = sqrt(l);
        for (int c = 0; c < 3; ++c)
            n[3 * t + c] = v[c] / l;
    }
    int nl = 0;
    while ((1 << nl) < (W > H ? W : H))
        ++nl;
    mf_prefilter_level *lv = calloc((size_t)nl, sizeof *lv);
    for (int l = 0; l < nl; ++l) {
        int w = W >> (l + 1), h = H >> (l + 1);
        w = w > 0 ? w : 1, h = h > 0 ? h : 1;
        size_t ne = (size_t)w * h * o.n_theta * o.n_phi;
        char p[3][1024];
        snprintf(p[0], sizeof p[0], "%s/ltc_mip%d.npy", dir, l + 1);
        snprintf(p[1], sizeof p[1], "%s/magnitude_mip%d.npy", dir, l + 1);
        snprintf(p[2], sizeof p[2], "%s/albedo_mip%d.npy", dir, l + 1);
        lv[l] = (mf_prefilter_level){.level = l + 1, .width = w, .height = h, .n_theta = o.n_theta, .n_phi = o.n_phi};
        lv[l].m = read_npy(p[0], 9 * ne), lv[l].magnitude = read_npy(p[1], ne), lv[l].albedo = read_npy(p[2], ne);
        if (!lv[l].m || !lv[l].magnitude || !lv[l].albedo) {
            fprintf(stderr, "%s: level %d: cannot read its .npy files (float32, %zu lobes)\n", dir, l + 1, ne);
            return 2;
        }
    }
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    struct timespec t0, t1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
    mf_status st = mf_prefilter_gate_run_ref(lv, nl, n, W, H, &o, &g);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
    long lobes = 0;
    for (int l = 0; l < nl; ++l)
        lobes += (long)lv[l].width * lv[l].height * o.n_theta * o.n_phi;
    double cpu = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    printf("gate: %ld lobes, %.3f s of process CPU (%.2f us per lobe)\n", lobes, cpu, 1e6 * cpu / (double)lobes);
    if (st != MF_OK) {
        fprintf(stderr, "gate: %s\n", mf_status_str(st));
        return 1;
    }
    printf("pass %d  energy %.6g (%s)  nan %ld  level %.6g (%s)\n", g.pass, g.worst_energy, g.where_energy,
           g.nan_entries, g.worst_level, g.where_level);
    printf("cont texel %.6g (%s)\ncont view %.6g (%s)\ncont grazing %.6g (%s)\nref error %.6g  jumps %.6g %.6g\n",
           g.worst_cont_texel, g.where_cont_texel, g.worst_cont_view, g.where_cont_view, g.worst_cont_grazing,
           g.where_cont_grazing, g.worst_ref_error, g.worst_jump_texel, g.worst_jump_view);
    printf("cross %.6g (%s)  cross_texel %.6g\n", g.worst_cont_cross, g.where_cont_cross, g.worst_cont_cross_texel);
    printf("excess %.6g (%s)\n", g.worst_cont_excess, g.where_cont_excess);
    printf("own fit, azimuths: owner %.6g (%s)\n", g.worst_cont_owner_view, g.where_cont_owner_view);
    printf("own fit: owner %.6g (%s)  dominated %.6g (%s)\n", g.worst_cont_owner, g.where_cont_owner,
           g.worst_cont_dominated, g.where_cont_dominated);
    printf("own fit, elevations: owner %.6g (%s)  dominated %.6g (%s)\n", g.worst_cont_owner_theta,
           g.where_cont_owner_theta, g.worst_cont_dominated_theta, g.where_cont_dominated_theta);
    const char *raw = getenv("MF_GATE_RAW"); /* the result's bytes, for comparing builds */
    if (raw) {
        FILE *f = fopen(raw, "wb");
        if (!f || fwrite(&g, sizeof g, 1, f) != 1 || fclose(f) != 0)
            return 1;
    }
    if (argc > 9 && !strcmp(argv[8], "corrupt"))
        corrupt(lv, nl, n, W, H, &o, atoi(argv[9]), argc > 10 ? strtoull(argv[10], NULL, 10) : 12345,
                argc > 11 ? argv[11] : "0123");
    for (int l = 0; l < nl; ++l)
        free(lv[l].m), free(lv[l].magnitude), free(lv[l].albedo);
    free(lv), free(n), mf_image_free(&img);
    return 0;
}
