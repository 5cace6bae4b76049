/* test_prefilter_gate_files.c -- the prefilter gate (mf_prefilter_gate_run_ref) run again on a table
 * `mfkit prefilter` wrote: its levels read back from DIR/ltc_mip<k>.npy, magnitude_mip<k>.npy and
 * albedo_mip<k>.npy, the normals decoded from the map as the command decodes them (unorm PNG, green
 * up, renormalised), the options (base, roughness, views) from the arguments.  A measuring tool for
 * docs/prefilter_log.md ("Gating continuity across texels"), not a CTest test: it prints every
 * figure of the gate's result.
 *
 * Usage: test_prefilter_gate_files DIR MAP NT NP [ggx|lambert] [ALPHA] [THREADS] [corrupt NCORR [SEED]]
 *   corrupt: then NCORR corruptions of each kind, one at a time on the good table, each gated and
 *   printed on one line: kind, level, the shading change (lobe_change), the gated checks' verdict and
 *   the continuity measures.  Kinds: 0 one matrix entry (among those >= 0.05 of the largest) scaled by
 *   1 + s, s log-uniform in [0.02, 1]; 1 the lobe swapped with its phi neighbour; 2 the lobe mirrored
 *   (x -> -x: its highlight on the other side of the view plane); 3 the lobe replaced by its texel
 *   neighbour's (x + 1, periodic) at the same view.  Levels drawn uniformly, except a 1 x 1 top level (no
 *   texel neighbours: the continuity measures do not cover it). */
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

static void corrupt(mf_prefilter_level *lv, int nl, const double *n, int W, int H, const mf_prefilter_options *o,
                    int ncorr, uint64_t seed)
{
    const int nt = o->n_theta, np = o->n_phi;
    for (int c = 0; c < 4 * ncorr; ++c) {
        int kind = c % 4;
        int nlt = nl - (lv[nl - 1].width == 1 && lv[nl - 1].height == 1 && nl > 1); /* not the 1 x 1 top level: no texel axis */
        int l = (int)(lcg(&seed) % (uint64_t)nlt);
        mf_prefilter_level *L = &lv[l];
        size_t nv = (size_t)nt * np, ne = (size_t)L->width * L->height * nv;
        size_t e = lcg(&seed) % ne, f = e;
        int b = (int)(e % (size_t)np);
        double s = 0.02 * pow(50.0, (double)lcg(&seed) / 2147483648.0);
        if (kind == 1)
            f = e - b + (size_t)((b + 1) % np);
        float se[10], sf[10];
        memcpy(se, L->m + 9 * e, 36), se[9] = L->magnitude[e];
        if (kind == 3) { /* texel neighbour x + 1 (periodic) at the same view */
            size_t t = e / nv, row = t / (size_t)L->width, col = t % (size_t)L->width;
            size_t g = (row * (size_t)L->width + (col + 1) % (size_t)L->width) * nv + e % nv;
            memcpy(L->m + 9 * e, L->m + 9 * g, 36), L->magnitude[e] = L->albedo[e] / L->albedo[g] * L->magnitude[g];
        } else if (kind == 2) {
            float *m = L->m + 9 * e;
            m[1] = -m[1], m[2] = -m[2], m[3] = -m[3], m[6] = -m[6];
        } else if (kind == 1) {
            memcpy(sf, L->m + 9 * f, 36), sf[9] = L->magnitude[f];
            memcpy(L->m + 9 * e, sf, 36), L->magnitude[e] = sf[9];
            memcpy(L->m + 9 * f, se, 36), L->magnitude[f] = se[9];
        } else {
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
        double ch = lobe_change(L, e, se, o);
        if (kind == 1)
            ch = fmax(ch, lobe_change(L, f, sf, o));
        mf_prefilter_gate g;
        mf_prefilter_gate_bounds_default(&g);
        if (mf_prefilter_gate_run_ref(lv, nl, n, W, H, o, &g) != MF_OK)
            exit(1);
        size_t t = e / nv;
        printf("C kind %d level %d texel %zu %zu view %zu %zu change %.5f gated %d cross %.5f excess %.5f "
               "cont %.5f %.5f %.5f\n", kind, L->level, t % (size_t)L->width, t / (size_t)L->width, e / (size_t)np % (size_t)nt,
               e % (size_t)np, ch, !(g.pass_energy && g.pass_nan && g.pass_level), g.worst_cont_cross,
               g.worst_cont_excess, g.worst_cont_texel, g.worst_cont_view, g.worst_cont_grazing);
        fflush(stdout);
        memcpy(L->m + 9 * e, se, 36), L->magnitude[e] = se[9];
        if (kind == 1)
            memcpy(L->m + 9 * f, sf, 36), L->magnitude[f] = sf[9];
    }
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
    const char *raw = getenv("MF_GATE_RAW"); /* the result's bytes, for comparing builds */
    if (raw) {
        FILE *f = fopen(raw, "wb");
        if (!f || fwrite(&g, sizeof g, 1, f) != 1 || fclose(f) != 0)
            return 1;
    }
    if (argc > 9 && !strcmp(argv[8], "corrupt"))
        corrupt(lv, nl, n, W, H, &o, atoi(argv[9]), argc > 10 ? strtoull(argv[10], NULL, 10) : 12345);
    for (int l = 0; l < nl; ++l)
        free(lv[l].m), free(lv[l].magnitude), free(lv[l].albedo);
    free(lv), free(n), mf_image_free(&img);
    return 0;
}
