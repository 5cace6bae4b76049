/*
 * study_prefilter_split.c -- one lobe or two, per footprint (issue 13; docs/prefilter.md, "One lobe or
 * two, per footprint").  `mfkit prefilter --lobes 2` splits every footprint of two or more distinct
 * normals.  A footprint whose halves' highlights overlap might be served as well by one lobe, and
 * would then cost one fit instead of two.  This program measures whether that is so: it reads two
 * `mfkit prefilter-eval` record files of the same run and records (`--out` of `prefilter-eval PF
 * --lobes 2` and of `prefilter-eval PF`), takes each footprint's mean squared error of mfkit's column
 * against the Monte Carlo truth in both, and bins the footprints by the angle between the halves' mean
 * normals of the prefilter's own 2-means split (mf_prefilter_split_two), in units of the base's alpha.
 * Per bin: footprints, the levels they come from, those where the two-lobe table is the better, and the
 * mean MSE of each.
 *
 *   study_prefilter_split --map NORMALMAP --alpha A --two EVAL2/prefilter_eval.csv
 *       --one EVAL1/prefilter_eval.csv
 * Unorm maps (8/16-bit) are decoded as mfkit prefilter's defaults do (green up); float maps raw.  The
 * angle does not depend on the green convention.
 */
#include "mfkit/fit/mf_image_oiio.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/io/mf_image.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SPLIT_MAX_LEVELS 13

typedef struct {
    int w, h;
    double *se; /* per texel: the sum of squared errors over its records */
    long *n;    /* and their count */
} split_level;

static int usage(FILE *to)
{
    fprintf(to, "usage: study_prefilter_split --map NORMALMAP --alpha A --two RECORDS.csv --one RECORDS.csv\n");
    return 2;
}

/* Reads a prefilter-eval record file into per-footprint error sums.  Returns 0, or 1 with a message. */
static int read_records(const char *path, split_level *L, int nl)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "study_prefilter_split: %s: cannot open\n", path);
        return 1;
    }
    static char line[8192];
    int col[5] = {-1, -1, -1, -1, -1}; /* level, row, col, truth, mfkit */
    const char *const names[5] = {"level", "row", "col", "truth", "mfkit"};
    if (!fgets(line, sizeof line, f)) {
        fprintf(stderr, "study_prefilter_split: %s: empty\n", path);
        fclose(f);
        return 1;
    }
    line[strcspn(line, "\r\n")] = '\0';
    int k = 0;
    for (char *t = strtok(line, ","); t; t = strtok(NULL, ","), ++k)
        for (int i = 0; i < 5; ++i)
            if (!strcmp(t, names[i]))
                col[i] = k;
    for (int i = 0; i < 5; ++i)
        if (col[i] < 0) {
            fprintf(stderr, "study_prefilter_split: %s: no column \"%s\" (not a prefilter-eval record file)\n", path,
                    names[i]);
            fclose(f);
            return 1;
        }
    long row = 1;
    while (fgets(line, sizeof line, f)) {
        ++row;
        double v[5] = {0};
        int got = 0;
        char *s = line;
        for (int c = 0; s && *s && *s != '\n'; ++c) {
            for (int i = 0; i < 5; ++i)
                if (c == col[i])
                    v[i] = strtod(s, NULL), ++got;
            s = strchr(s, ',');
            s = s ? s + 1 : NULL;
        }
        int l = (int)v[0], y = (int)v[1], x = (int)v[2];
        if (got != 5 || l < 1 || l > nl || y < 0 || y >= L[l - 1].h || x < 0 || x >= L[l - 1].w || !isfinite(v[3]) ||
            !isfinite(v[4])) {
            fprintf(stderr, "study_prefilter_split: %s, line %ld: not a record of this map's footprints\n", path, row);
            fclose(f);
            return 1;
        }
        size_t t = (size_t)y * L[l - 1].w + x;
        L[l - 1].se[t] += (v[4] - v[3]) * (v[4] - v[3]);
        L[l - 1].n[t]++;
    }
    fclose(f);
    return 0;
}

int main(int argc, char **argv)
{
    const char *map = NULL, *two = NULL, *one = NULL;
    double alpha = 0.0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "-h") || !strcmp(argv[i], "--help")) {
            usage(stdout);
            return 0;
        }
        if (i + 1 >= argc)
            return usage(stderr);
        const char *a = argv[i], *v = argv[++i];
        if (!strcmp(a, "--map"))
            map = v;
        else if (!strcmp(a, "--two"))
            two = v;
        else if (!strcmp(a, "--one"))
            one = v;
        else if (!strcmp(a, "--alpha"))
            alpha = strtod(v, NULL);
        else
            return usage(stderr);
    }
    if (!map || !two || !one || !(alpha > 0.0 && alpha <= 1.0))
        return usage(stderr);

    char msg[4400];
    mf_image_set_backend(mf_image_oiio_backend());
    mf_image img;
    mf_image_info info;
    mf_status st = mf_image_read_ex(map, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, "study_prefilter_split: %s\n", msg[0] ? msg : mf_status_str(st));
        return 3;
    }
    if (img.channels < 3) {
        fprintf(stderr, "study_prefilter_split: %s: %d channels, need 3 or 4\n", map, img.channels);
        return 2;
    }
    int unorm = !strncmp(info.pixel_type, "uint", 4), W = img.width, H = img.height;
    double *nrm = malloc(sizeof(double) * 3 * (size_t)W * H);
    if (!nrm)
        return 3;
    for (size_t t = 0; t < (size_t)W * H; ++t) {
        double n[3];
        for (int c = 0; c < 3; ++c)
            n[c] = unorm ? 2.0 * (double)img.pixels[t * img.channels + c] - 1.0 : (double)img.pixels[t * img.channels + c];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int c = 0; c < 3; ++c)
            nrm[3 * t + c] = n[c] / l;
    }
    mf_image_free(&img);
    mf_image_info_free(&info);

    split_level L[2][SPLIT_MAX_LEVELS];
    int nl = 0;
    while (nl < SPLIT_MAX_LEVELS && ((W >> nl) > 1 || (H >> nl) > 1))
        ++nl;
    for (int s = 0; s < 2; ++s)
        for (int l = 0; l < nl; ++l) {
            int w = W >> (l + 1), h = H >> (l + 1);
            L[s][l].w = w < 1 ? 1 : w, L[s][l].h = h < 1 ? 1 : h;
            L[s][l].se = calloc((size_t)L[s][l].w * L[s][l].h, sizeof(double));
            L[s][l].n = calloc((size_t)L[s][l].w * L[s][l].h, sizeof(long));
            if (!L[s][l].se || !L[s][l].n)
                return 3;
        }
    if (read_records(two, L[0], nl) || read_records(one, L[1], nl))
        return 2;

    /* the bins of the halves' angle, in units of alpha; "one normal": footprints that do not split */
    const double edge[] = {0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 10.0, INFINITY};
    enum { NB = sizeof edge / sizeof edge[0] - 1 };
    long cnt[NB + 1] = {0}, better[NB + 1] = {0};
    double m2[NB + 1] = {0}, m1[NB + 1] = {0};
    unsigned levels[NB + 1] = {0};
    double *foot = malloc(sizeof(double) * 3 * (size_t)W * H);
    int *side = malloc(sizeof(int) * (size_t)W * H);
    if (!foot || !side)
        return 3;
    for (int l = 0; l < nl; ++l)
        for (int y = 0; y < L[0][l].h; ++y)
            for (int x = 0; x < L[0][l].w; ++x) {
                size_t t = (size_t)y * L[0][l].w + x;
                if (!L[0][l].n[t] && !L[1][l].n[t])
                    continue;
                if (L[0][l].n[t] != L[1][l].n[t]) {
                    fprintf(stderr, "study_prefilter_split: level %d texel (%d, %d): %ld records in %s, %ld in %s: "
                                    "not evaluations of the same records\n", l + 1, x, y, L[0][l].n[t], two,
                            L[1][l].n[t], one);
                    return 2;
                }
                int fw = W / L[0][l].w, fh = H / L[0][l].h, q = 0;
                for (int v = y * fh; v < (y + 1) * fh; ++v)
                    for (int u = x * fw; u < (x + 1) * fw; ++u, ++q)
                        memcpy(foot + 3 * q, nrm + 3 * ((size_t)v * W + u), sizeof(double) * 3);
                int b = NB; /* one normal */
                if (mf_prefilter_split_two(foot, q, side) > 0) {
                    double c[2][3] = {{0, 0, 0}, {0, 0, 0}};
                    for (int i = 0; i < q; ++i)
                        for (int k = 0; k < 3; ++k)
                            c[side[i]][k] += foot[3 * i + k];
                    double l0 = sqrt(c[0][0] * c[0][0] + c[0][1] * c[0][1] + c[0][2] * c[0][2]);
                    double l1 = sqrt(c[1][0] * c[1][0] + c[1][1] * c[1][1] + c[1][2] * c[1][2]);
                    double cs = (c[0][0] * c[1][0] + c[0][1] * c[1][1] + c[0][2] * c[1][2]) / (l0 * l1);
                    double ang = acos(fmin(1.0, fmax(-1.0, cs))) / alpha;
                    for (b = 0; b + 1 < NB && ang >= edge[b + 1]; ++b)
                        ;
                }
                double e2 = L[0][l].se[t] / L[0][l].n[t], e1 = L[1][l].se[t] / L[1][l].n[t];
                cnt[b]++, better[b] += e2 < e1, m2[b] += e2, m1[b] += e1, levels[b] |= 1u << (l + 1);
            }
    printf("| halves' angle / alpha | footprints | levels | two lobes better | mean MSE, two lobes | mean MSE, one lobe | "
           "ratio |\n|---|---|---|---|---|---|---|\n");
    for (int b = 0; b <= NB; ++b) {
        if (!cnt[b])
            continue;
        char lv[64] = "";
        for (int l = 1; l <= nl; ++l)
            if (levels[b] >> l & 1u)
                snprintf(lv + strlen(lv), sizeof lv - strlen(lv), "%s%d", lv[0] ? ", " : "", l);
        char bin[48];
        if (b == NB)
            snprintf(bin, sizeof bin, "one normal");
        else if (isinf(edge[b + 1]))
            snprintf(bin, sizeof bin, ">= %g", edge[b]);
        else
            snprintf(bin, sizeof bin, "[%g, %g)", edge[b], edge[b + 1]);
        printf("| %s | %ld | %s | %ld | %.3g | %.3g | %.2f |\n", bin, cnt[b], lv, better[b], m2[b] / cnt[b],
               m1[b] / cnt[b], m1[b] > 0.0 ? m2[b] / m1[b] : NAN);
    }
    for (int s = 0; s < 2; ++s)
        for (int l = 0; l < nl; ++l)
            free(L[s][l].se), free(L[s][l].n);
    free(nrm), free(foot), free(side);
    return 0;
}
