/*
 * cli_prefilter.c -- `mfkit prefilter NORMALMAP --out DIR`: one LTC per texel of every MIP level
 * >= 1 and per tabulated view, fitted to the effective BRDF of the texel's footprint
 * (mf_prefilter.h) [Nahmias 2022, Ch. 3].  Level 0 is not stored: there a texel's effective BRDF
 * is the base BRDF about its own normal, shaded with the base BRDF's own (isotropic) LTC table.
 * Exit 0 success, 2 usage or input error (one line, no output), 3 I/O error, 4 fit failure.
 * All files are committed together (mf_io_atomic_commit_all): a failure leaves no output.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include <stdlib.h>
#include <string.h>

static const char *const k_cmd = "prefilter";
static const char *const k_green_names[] = {"up", "down", NULL};
static const char *const k_encoding_names[] = {"auto", "unorm", "raw", NULL};

enum { P_OUT, P_ROUGHNESS, P_VIEWS, P_GREEN, P_ENCODING, P_TOLERANCE, P_THREADS, P_SAMPLES, P_NOPTS };
static const cli_opt k_opts[P_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "output directory (created if missing)"},
    {.name = "--roughness", .metavar = "A", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = 1.0, .lo_open = 1, .def = "0.1",
     .help = "base GGX roughness alpha"},
    {.name = "--views", .metavar = "TxP", .kind = CLI_OPT_STRING, .def = "8x16",
     .help = "elevations over [0, 0.999 pi/2] x azimuths over [0, 2 pi)"},
    {.name = "--green", .kind = CLI_OPT_ENUM, .choices = k_green_names, .def = "up",
     .help = "green is +y up (OpenGL) or down (DirectX)"},
    {.name = "--encoding", .kind = CLI_OPT_ENUM, .choices = k_encoding_names, .def = "auto",
     .help = "unorm n = 2c - 1, raw n = c; auto: unorm for unsigned integer files (PNG), raw for float (EXR)"},
    {.name = "--normal-tolerance", .metavar = "E", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = INFINITY,
     .def = "1e-3 + sqrt(3)/(2^bits - 1) for integer files, 1e-3 for float files", .help = "accepted | |n| - 1 |"},
    {.name = "--threads", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 256, .def = "1",
     .help = "worker threads (the output does not depend on it)"},
    {.name = "--samples", .metavar = "N", .kind = CLI_OPT_INT, .lo = 64, .hi = 1 << 20, .pow2 = 1, .def = "4096",
     .help = "directions per fit"},
};
static const cli_command k_prefilter_cmd = {
    .name = "prefilter",
    .synopsis = "NORMALMAP",
    .min_pos = 1,
    .max_pos = 1,
    .description =
        "Fits, for every MIP level k >= 1 (box footprints of 2^k x 2^k texels; width and height powers of\n"
        "two), every texel and every view, one anisotropic LTC to the footprint's effective BRDF (the\n"
        "average of the base GGX rotated to each texel's normal, Nahmias 2022, Eq. 2.36, over all texels)\n"
        "in the view-azimuth-aligned frame.  Level 0: shade each texel with the isotropic GGX LTC table.\n"
        "Writes DIR/prefilter.json and per level DIR/ltc_mip<k>.npy (h, w, n_theta, n_phi, 3, 3) float32\n"
        "forward matrices and DIR/magnitude_mip<k>.npy (h, w, n_theta, n_phi) float32 albedos.\n",
    .opts = k_opts,
    .nopts = P_NOPTS,
    .epilog = "exit status: 0 success, 2 usage or input error, 3 I/O error, 4 fit failure\n",
};

#if !defined(MFKIT_CLI_HAVE_IMAGE) || !defined(MFKIT_CLI_HAVE_SOLVER)

int cli_prefilter(int argc, char **argv)
{
    return cli_opt_unavailable(&k_prefilter_cmd, k_cmd, "Ceres and OpenImageIO", "MFKIT_WITH_CERES/MFKIT_WITH_OIIO",
                               argc, argv);
}

#else

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/io/mf_io.h"
#include "mfkit/mfkit.h"

#include <time.h>

static int uint_bits(const char *type)
{
    if (type && !strncmp(type, "uint", 4)) {
        int b = atoi(type + 4);
        return b > 0 ? b : 8;
    }
    return 0;
}

static void npy_header(mf_buf *b, const char *shape)
{
    char hdr[200];
    int hl = snprintf(hdr, sizeof hdr, "{'descr': '<f4', 'fortran_order': False, 'shape': %s, }", shape);
    int pad = (64 - (10 + hl + 1) % 64) % 64;
    mf_buf_put(b, "\x93NUMPY\x01\x00", 8);
    mf_buf_u16le(b, (uint16_t)(hl + pad + 1));
    mf_buf_put(b, hdr, (size_t)hl);
    for (int i = 0; i < pad; ++i)
        mf_buf_put(b, " ", 1);
    mf_buf_put(b, "\n", 1);
}

static int write_file(mf_io_atomic *a, const char *path, const mf_buf *b, char *msg, size_t msg_size)
{
    if (mf_io_atomic_begin(a, path, msg, msg_size) != MF_OK)
        return 0;
    if (fwrite(b->data, 1, b->len, a->file) != b->len) {
        snprintf(msg, msg_size, "%.900s: write failed", path);
        return 0;
    }
    return 1;
}

int cli_prefilter(int argc, char **argv)
{
    cli_val v[P_NOPTS];
    const char *pos[1];
    int npos = 0;
    int prc = cli_opt_parse(&k_prefilter_cmd, argc - 1, argv + 1, ~0u, k_cmd, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_prefilter_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *input = pos[0], *dir = v[P_OUT].s;
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    if (v[P_ROUGHNESS].set)
        o.alpha = v[P_ROUGHNESS].d;
    if (v[P_THREADS].set)
        o.threads = (int)v[P_THREADS].i;
    if (v[P_SAMPLES].set)
        o.samples = (int)v[P_SAMPLES].i;
    if (v[P_VIEWS].set) {
        char tail;
        if (sscanf(v[P_VIEWS].s, "%dx%d%c", &o.n_theta, &o.n_phi, &tail) != 2 || o.n_theta < 2 || o.n_theta > 256 ||
            o.n_phi < 1 || o.n_phi > 256)
            return cli_error(k_cmd, "--views %s: expected TxP, 2..256 elevations x 1..256 azimuths", v[P_VIEWS].s);
    }
    int green_down = v[P_GREEN].set && v[P_GREEN].i == 1;
    int encoding = v[P_ENCODING].set ? (int)v[P_ENCODING].i : 0;

    mf_image img;
    mf_image_info info;
    char msg[1024];
    mf_status st = mf_image_read_ex(input, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        cli_error(k_cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return st == MF_ERR_UNSUPPORTED ? CLI_EXIT_USAGE : CLI_EXIT_IO;
    }
    int rc = 0;
    double *normals = NULL;
    mf_prefilter_level *levels = NULL;
    int nlevels = 0;
    if (img.channels != 3 && img.channels != 4) {
        rc = cli_error(k_cmd, "%s: a normal map needs 3 channels (R, G, B = n.x, n.y, n.z, or 4 with alpha), it has %d",
                       input, img.channels);
        goto done;
    }
    if (img.width > 4096 || img.height > 4096 || (img.width & (img.width - 1)) || (img.height & (img.height - 1)) ||
        (img.width == 1 && img.height == 1)) {
        rc = cli_error(k_cmd, "%s: size %d x %d: width and height must be powers of two up to 4096, not both 1", input,
                       img.width, img.height);
        goto done;
    }
    int bits = uint_bits(info.pixel_type);
    int unorm = encoding == 1 || (encoding == 0 && bits > 0);
    double tol = v[P_TOLERANCE].set ? v[P_TOLERANCE].d
                                    : 1e-3 + (bits > 0 && bits < 32 ? sqrt(3.0) / (ldexp(1.0, bits) - 1.0) : 0.0);
    normals = malloc(sizeof(double) * 3 * (size_t)img.width * img.height);
    if (!normals) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
        goto done;
    }
    for (int j = 0; j < img.height; ++j)
        for (int i = 0; i < img.width; ++i) {
            size_t t = (size_t)j * img.width + i;
            const float *p = img.pixels + t * (size_t)img.channels;
            double n[3];
            for (int c = 0; c < 3; ++c) {
                if (!isfinite(p[c])) {
                    rc = cli_error(k_cmd, "%s: texel (%d, %d) (column, row from the top): channel %c is %s", input, i, j,
                                   "RGB"[c], isnan(p[c]) ? "NaN" : "infinite");
                    goto done;
                }
                n[c] = unorm ? 2.0 * (double)p[c] - 1.0 : (double)p[c];
            }
            if (green_down)
                n[1] = -n[1];
            double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(fabs(len - 1.0) <= tol) || !(n[2] > 0.0)) {
                rc = cli_error(k_cmd,
                               "%s: texel (%d, %d) (column, row from the top): normal (%.6g, %.6g, %.6g) is not a unit "
                               "vector within %.3g with n.z > 0 (see --encoding, --normal-tolerance)",
                               input, i, j, n[0], n[1], n[2], tol);
                goto done;
            }
            for (int c = 0; c < 3; ++c)
                normals[3 * t + c] = n[c] / len;
        }
    if (mf_io_make_dirs(dir, msg, sizeof msg) != MF_OK) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: %s", dir, msg);
        goto done;
    }
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    st = mf_prefilter_run(normals, img.width, img.height, &o, &levels, &nlevels, msg, sizeof msg);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (st != MF_OK) {
        rc = cli_error(k_cmd, "%s: %s", input, msg[0] ? msg : mf_status_str(st));
        if (st != MF_ERR_DOMAIN)
            rc = st == MF_ERR_ALLOC ? CLI_EXIT_IO : CLI_EXIT_FIT;
        goto done;
    }
    double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    {
        int nf = 2 * nlevels + 1;
        mf_io_atomic *files = calloc((size_t)nf, sizeof *files);
        mf_buf man = {0};
        long lobes = 0;
        int ok = files != NULL;
        mf_buf_printf(&man,
                      "{\n  \"kind\": \"ltc_prefilter\",\n  \"map\": \"%s\",\n  \"width\": %d,\n  \"height\": %d,\n"
                      "  \"base_brdf\": {\"model\": \"ggx\", \"alpha\": %.17g},\n"
                      "  \"frame\": \"view-azimuth-aligned: normals rotated by -phi about z, view (sin theta, 0, cos "
                      "theta); M forward, divided by the norm of its last column\",\n"
                      "  \"below_horizon\": \"texel-frame view cosine clamped to %.17g at its azimuth (Nahmias 2022)\",\n"
                      "  \"theta\": [",
                      input, img.width, img.height, o.alpha, MF_PREFILTER_COS_MIN);
        for (int a = 0; a < o.n_theta; ++a)
            mf_buf_printf(&man, "%s%.17g", a ? ", " : "", mf_prefilter_theta(&o, a));
        mf_buf_printf(&man, "],\n  \"phi\": [");
        for (int b = 0; b < o.n_phi; ++b)
            mf_buf_printf(&man, "%s%.17g", b ? ", " : "", mf_prefilter_phi(&o, b));
        mf_buf_printf(&man, "],\n  \"fit\": {\"fitter\": \"mf_ltcfit_aniso general entry, 7-parameter lobe chart\", "
                            "\"samples\": %d, \"seed\": 1},\n  \"level0\": \"not stored: isotropic GGX LTC per texel\",\n"
                            "  \"levels\": [\n",
                      o.samples);
        for (int l = 0; l < nlevels && ok; ++l) {
            mf_prefilter_level *lv = &levels[l];
            char path[4096], shape[128], mname[64], aname[64];
            snprintf(mname, sizeof mname, "ltc_mip%d.npy", lv->level);
            snprintf(aname, sizeof aname, "magnitude_mip%d.npy", lv->level);
            size_t n = (size_t)lv->width * lv->height * o.n_theta * o.n_phi;
            mf_buf b = {0};
            snprintf(shape, sizeof shape, "(%d, %d, %d, %d, 3, 3)", lv->height, lv->width, o.n_theta, o.n_phi);
            npy_header(&b, shape);
            for (size_t i = 0; i < 9 * n; ++i)
                mf_buf_f32le(&b, lv->m[i]);
            snprintf(path, sizeof path, "%s/%s", dir, mname);
            ok = write_file(&files[2 * l], path, &b, msg, sizeof msg);
            mf_buf_free(&b);
            if (!ok)
                break;
            snprintf(shape, sizeof shape, "(%d, %d, %d, %d)", lv->height, lv->width, o.n_theta, o.n_phi);
            npy_header(&b, shape);
            for (size_t i = 0; i < n; ++i)
                mf_buf_f32le(&b, lv->magnitude[i]);
            snprintf(path, sizeof path, "%s/%s", dir, aname);
            ok = write_file(&files[2 * l + 1], path, &b, msg, sizeof msg);
            mf_buf_free(&b);
            mf_buf_printf(&man,
                          "    {\"level\": %d, \"width\": %d, \"height\": %d, \"matrices\": \"%s\", \"magnitude\": \"%s\", "
                          "\"lobes\": %ld, \"worst_residual\": %.6g, \"worst_albedo_err\": %.6g, \"not_converged\": %d}%s\n",
                          lv->level, lv->width, lv->height, mname, aname, lv->lobes, lv->worst_residual,
                          lv->worst_albedo_err, lv->not_converged, l + 1 < nlevels ? "," : "");
            lobes += lv->lobes;
        }
        mf_buf_printf(&man, "  ],\n  \"lobes\": %ld\n}\n", lobes);
        if (ok) {
            char path[4096];
            snprintf(path, sizeof path, "%s/prefilter.json", dir);
            ok = write_file(&files[nf - 1], path, &man, msg, sizeof msg);
        }
        mf_buf_free(&man);
        if (ok && mf_io_atomic_commit_all(files, (size_t)nf, msg, sizeof msg) == MF_OK) {
            fprintf(stderr, "mfkit prefilter: %ld lobes in %.3f s (%.3f ms per lobe, %d thread%s)\n", lobes, secs,
                    lobes ? 1e3 * secs / lobes : 0.0, o.threads, o.threads > 1 ? "s" : "");
        } else {
            if (files && !ok)
                mf_io_atomic_abort_all(files, (size_t)nf);
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
        }
        free(files);
    }
done:
    free(normals);
    mf_prefilter_levels_free(levels, nlevels);
    mf_image_free(&img);
    mf_image_info_free(&info);
    return rc;
}

#endif
