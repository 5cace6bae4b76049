/*
 * cli_prefilter.c -- `mfkit prefilter NORMALMAP --out DIR`: one LTC per texel of every MIP level
 * >= 1 and per tabulated view, fitted to the effective BRDF of the texel's footprint
 * (mf_prefilter.h) [Nahmias 2022, Ch. 3].  Level 0 is not stored: there a texel's effective BRDF
 * is the base BRDF about its own normal, shaded with the base BRDF's own (isotropic) LTC table.
 *
 * The pipeline (docs/prefilter.md):
 *   tiles   the map is cut into --tile x --tile regions, each fitted for the levels whose
 *           footprints lie inside it; every texel of a higher level is a tile of its own (its
 *           footprint).  mf_prefilter_run_tile fits a tile; a footprint's lobes depend only on its
 *           normals and the options, so the tiling does not change a bit of the output.
 *   albedos before the tiles, the top-level albedos of every region block (mf_prefilter_albedo_level,
 *           DIR/.prefilter-work/albedo_<b>.bin); a footprint tile reduces its footprint's albedos
 *           from its blocks' (the mean of the children's, in the library's fixed order), so it
 *           holds no level-0 albedos.  Done in the first slice, whatever --max-tiles.
 *   work    each finished tile is written atomically to DIR/.prefilter-work/tile_<k>.bin, the
 *           checkpoint: a rerun of the same command (same map, options, fitter revision and work
 *           format, recorded in run.txt there) skips the tiles present.  A region tile's file also
 *           holds the gate's reference R of its lobes in its two outer rings, the only ones rank 0
 *           reads (mf_prefilter_gate_reference, computed by the worker that fitted it from the tile's
 *           own normals; mf_prefilter_gate_ref_cols).  SIGINT/SIGTERM and --max-tiles
 *           stop between tiles and keep the checkpoint.
 *   ranks   under mpirun (built with MFKIT_WITH_MPI) rank r of K fits every K-th tile from the
 *           r-th, largest footprints first (and every K-th albedo block before them, then a
 *           barrier); after a barrier rank 0 assembles.  One process and K
 *           ranks fit the same tiles with the same code: the same bits.
 *   output  rank 0 streams every level's .npy (matrices, magnitudes, albedos) (header first, then rows, read tile by tile) and
 *           its three EXR view atlases, writes the lookup snippets and prefilter.json, and commits
 *           them all together (mf_io_atomic_commit_all); then removes the work directory.
 * Memory: the map's normals, the fits of the tiles in flight (--threads N fits N tiles at once
 * when there are enough: a region tile its texels' albedos and its lobes, a footprint tile its
 * sub-map and one fit, whose clustering holds 80 bytes per footprint texel for a moment), the
 * albedo blocks (16 bytes per block and view) and a few rows of each level.
 * Gate: rank 0 streams the levels row by row from the tiles into the output files and the gate
 * (mf_prefilter_gate_stream_*: mf_prefilter_gate_run_ref's result, holding a few rows per level,
 * each row's columns split over --threads, the same result on any count) before committing; its
 * result goes into prefilter.json.  The region levels' reference rows come from the tile files
 * (mf_prefilter_gate_stream_row_ref: the same bits), so rank 0 no longer computes level 1's
 * reference, the gate's largest part.
 * Tables: --base both (the default) runs the pipeline twice, the specular GGX table into DIR, then the
 * diffuse Lambert table into DIR/diffuse; the specular checkpoint is kept until the diffuse table is
 * written, so a rerun after a stop in either table resumes it.
 * Exit 0 success, 1 gate failed (nothing written unless --force), 2 usage or input error (one line, no output),
 * 3 I/O error, 4 fit failure, 75 stopped by --max-tiles and 130 interrupted (both resumable: rerun
 * the same command).
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
static const char *const k_base_names[] = {"ggx", "lambert", "both", NULL};

enum { P_OUT, P_ROUGHNESS, P_VIEWS, P_GREEN, P_ENCODING, P_TOLERANCE, P_THREADS, P_SAMPLES, P_TILE, P_MAX_TILES, P_BASE, P_NO_KEEP_ALBEDO, P_FORCE, P_DIFFUSE_VIEWS, P_QUIET, P_SEED, P_LOBES, P_NO_REUSE, P_NOPTS };
static const cli_opt k_opts[P_NOPTS] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "output directory (created if missing)"},
    {.name = "--roughness", .metavar = "A", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = 1.0, .lo_open = 1, .def = "0.1",
     .help = "base GGX roughness alpha (the fitter and gate are tuned at 0.1; at 0.05 the gate passes on the "
             "shipped maps and fails on larger bump maps, at 0.03 it fails: docs/prefilter.md, "
             "\"Fitter revision 11\")"},
    {.name = "--views", .metavar = "TxP", .kind = CLI_OPT_STRING, .def = "8x16 (ggx), 2x4 (lambert)",
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
    {.name = "--tile", .metavar = "T", .kind = CLI_OPT_INT, .lo = 2, .hi = 4096, .pow2 = 1, .def = "64",
     .help = "tile side in level-0 texels (the lobes do not depend on it; memory and resume granularity do)"},
    {.name = "--max-tiles", .metavar = "N", .kind = CLI_OPT_INT, .lo = 0, .hi = 1 << 30, .def = "all",
     .help = "fit at most N new tiles in this process, then stop (exit 75; rerun to resume)"},
    {.name = "--base", .kind = CLI_OPT_ENUM, .choices = k_base_names, .def = "both",
     .help = "base BRDF: both tables (specular GGX in DIR, Lambert diffuse in DIR/diffuse), or only specular GGX "
             "(--roughness) or only Lambert diffuse (default views 2x4) in DIR"},
    {.name = "--no-keep-albedo", .kind = CLI_OPT_FLAG,
     .help = "magnitude = the effective BRDF's albedo (the lobe loses its mass below the horizon, as in Nahmias "
             "2022); the gate's energy check then fails at grazing views"},
    {.name = "--force", .kind = CLI_OPT_FLAG,
     .help = "write the tables even when the gate fails (the manifest marks them: \"forced\": true)"},
    {.name = "--diffuse-views", .metavar = "TxP", .kind = CLI_OPT_STRING, .def = "2x4",
     .help = "the diffuse table's views with --base both (--views sets the specular table's)"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no progress on stderr (shown only on a terminal anyway)"},
    {.name = "--seed", .metavar = "S", .kind = CLI_OPT_U64, .def = "1",
     .help = "scramble of the fits' direction sets (both tables; recorded in the manifest and checkpoint)"},
    {.name = "--lobes", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 2, .def = "1",
     .help = "2: also two lobes per entry for the specular table, DIR/lobe_a and DIR/lobe_b (the 2-means halves "
             "of each footprint's normals; a renderer sums their shading), each a table of the same files "
             "(docs/prefilter.md, \"Two lobes per entry\"); about 2x the specular fitting time"},
    {.name = "--no-reuse", .kind = CLI_OPT_FLAG,
     .help = "fit every footprint, also those identical to one fitted before in the same tile (by default they "
             "get a copy of its lobes: the same bits; docs/prefilter.md, \"Identical footprints are fitted once\")"},
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
        "By default (--base both) it writes the specular GGX table in DIR, then the diffuse (Lambert) table,\n"
        "the same files with its own manifest, in DIR/diffuse (views --diffuse-views, default 2x4);\n"
        "--base ggx or --base lambert writes that one table in DIR.\n"
        "Writes DIR/prefilter.json and per level DIR/ltc_mip<k>.npy (h, w, n_theta, n_phi, 3, 3) float32\n"
        "forward matrices, DIR/albedo_mip<k>.npy (h, w, n_theta, n_phi) float32 effective-BRDF albedos and\n"
        "DIR/magnitude_mip<k>.npy, the magnitudes that keep them (albedo / the lobe's mass above the horizon:\n"
        "may exceed 1), the EXR view atlases DIR/prefilter_mip<k>_{0,1,2}.exr and the lookup\n"
        "DIR/prefilter_lookup.{glsl,hlsl} (docs/prefilter.md).  The gate (energy within 1 %, no NaN, parents\n"
        "against children) runs before anything is written: on failure, exit 1 and nothing written unless\n"
        "--force.  Works tile by tile with a checkpoint in DIR/.prefilter-work: rerunning an\n"
        "interrupted command resumes it.  Under mpirun (MFKIT_WITH_MPI builds) the ranks share the tiles\n"
        "and write the same bits as one process.  --lobes 2 adds the two-lobe specular table: DIR/lobe_a and\n"
        "DIR/lobe_b, one table per half of each footprint's 2-means split of its normals; a renderer shades both\n"
        "and sums.  Each half is gated on energy and NaN, and the two-lobe gate runs the one-lobe gate's checks\n"
        "on the halves' summed shading before either is written.\n",
    .opts = k_opts,
    .nopts = P_NOPTS,
    .epilog = "exit status: 0 success, 1 gate failed, 2 usage or input error, 3 I/O error, 4 fit failure,\n"
              "75 stopped by --max-tiles, 130 interrupted (75 and 130 keep the checkpoint: rerun the same command\n"
              "to resume)\n",
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
#include "mfkit/io/mf_json.h"
#include "mfkit/mfkit.h"

#include <dirent.h>
#include <errno.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <time.h>
#include <unistd.h>

#ifdef MFKIT_CLI_HAVE_MPI
#include <mpi.h>
#endif

enum { PF_EXIT_INCOMPLETE = 75 };
#define PF_WORK ".prefilter-work"
#define PF_TILE_MAGIC "MFPFTIL5" /* 3: region tiles carry the gate's reference R; 4: only where rank 0 reads it;
                                     5: the gate part holds own fit across elevations */

/* set by the handler; an int is written atomically on every platform mfkit builds on */
static volatile int g_pf_cancel = 0;
static void pf_on_signal(int sig)
{
    (void)sig;
    g_pf_cancel = 1;
}

static int uint_bits(const char *type)
{
    if (type && !strncmp(type, "uint", 4)) {
        int b = atoi(type + 4);
        return b > 0 ? b : 8;
    }
    return 0;
}

/* ---- the tiling ------------------------------------------------------------------------------- */

/* A tile: the level-0 texels [x0, x0 + w) x [y0, y0 + h), fitted for levels first..last. */
typedef struct { int x0, y0, w, h, first, last; } pf_tile;

/* Level l of the output: tiles base + gy * nx + gx (gy < ny, gx < nx), each covering tw x th
 * texels of the level; the level is record `rec` of each of them. */
typedef struct { int level, w, h, nx, ny, tw, th, rec; long base; } pf_plan;

/* One level of a tile file (native byte order: the work files stay on the machines that wrote them). */
typedef struct {
    int32_t level, w, h, not_converged;
    int64_t iterations, lobes, off_m, off_mag, off_alb;
    int64_t off_ref;  /* a region tile's gate reference R (MF_PREFILTER_GATE_NLIGHTS doubles per lobe) of the
                         entries rank 0 reads (pf_ref_kept), row by row; 0: none */
    int64_t off_part; /* a region tile's part of the gate (mf_prefilter_gate_part); 0: none */
    double worst_residual, worst_albedo_err;
} pf_rec;

/* The texels of rows [0, y_end) of a region tile's w x h level whose R the tile file holds
 * (mf_prefilter_gate_ref_cols: the two outer rings). */
static size_t pf_ref_kept(int w, int h, int y_end)
{
    size_t n = 0;
    for (int y = 0; y < y_end; ++y) {
        int c[4], k = mf_prefilter_gate_ref_cols(w, h, y, c);
        n += (size_t)(c[1] - c[0]) + (k == 2 ? (size_t)(c[3] - c[2]) : 0);
    }
    return n;
}

static int ilog2_levels(int w, int h)
{
    int n = 0;
    while ((w >> n) > 1 || (h >> n) > 1)
        ++n;
    return n;
}

/* plans[l - 1] for l = 1..nl; *tiles allocated. */
static long pf_make_tiles(int W, int H, int T, pf_plan *plans, pf_tile **tiles)
{
    int nl = ilog2_levels(W, H);
    int rw = W < T ? W : T, rh = H < T ? H : T, lr = ilog2_levels(rw, rh);
    int ntx = W / rw, nty = H / rh;
    long n = (long)ntx * nty;
    for (int l = lr + 1; l <= nl; ++l)
        n += (long)(W >> l > 0 ? W >> l : 1) * (H >> l > 0 ? H >> l : 1);
    pf_tile *t = malloc(sizeof *t * (size_t)n);
    if (!t)
        return -1;
    long k = 0;
    for (int cy = 0; cy < nty; ++cy)
        for (int cx = 0; cx < ntx; ++cx)
            t[k++] = (pf_tile){cx * rw, cy * rh, rw, rh, 1, lr};
    for (int l = 1; l <= lr; ++l)
        plans[l - 1] = (pf_plan){l, W >> l > 0 ? W >> l : 1, H >> l > 0 ? H >> l : 1, ntx, nty,
                                 rw >> l > 0 ? rw >> l : 1, rh >> l > 0 ? rh >> l : 1, l - 1, 0};
    for (int l = lr + 1; l <= nl; ++l) {
        int lw = W >> l > 0 ? W >> l : 1, lh = H >> l > 0 ? H >> l : 1, fw = W / lw, fh = H / lh;
        plans[l - 1] = (pf_plan){l, lw, lh, lw, lh, 1, 1, 0, k};
        for (int r = 0; r < lh; ++r)
            for (int c = 0; c < lw; ++c)
                t[k++] = (pf_tile){c * fw, r * fh, fw, fh, l, l};
    }
    *tiles = t;
    return n;
}

static void tile_path(char *out, size_t size, const char *dir, long k)
{
    snprintf(out, size, "%s/" PF_WORK "/tile_%07ld.bin", dir, k);
}

/* The albedo base: the albedos (value, error per view) of the top level lr of every region block
 * (rw x rh texels, nbx x nby of them, row-major), computed once per block
 * (mf_prefilter_albedo_level, work file albedo_<b>.bin) and read by every rank; a footprint tile
 * reduces its footprint's albedos from its blocks' (mf_prefilter_run_tile), so it holds no level-0
 * albedos.  alb NULL: no footprint tiles. */
typedef struct { int rw, rh, lr, nbx, nby; double *alb; } pf_base;
#define PF_ALB_MAGIC "MFPFALB1"

static void block_path(char *out, size_t size, const char *dir, long b)
{
    snprintf(out, size, "%s/" PF_WORK "/albedo_%07ld.bin", dir, b);
}

/* Block b's albedo base, written atomically.  Returns a CLI exit code (0 ok), message printed. */
static int pf_run_block(const double *normals, int W, const mf_prefilter_options *o, const pf_base *ab, long b,
                        const char *path, const char *input)
{
    char msg[1024];
    size_t nv = (size_t)o->n_theta * o->n_phi;
    int x0 = (int)(b % ab->nbx) * ab->rw, y0 = (int)(b / ab->nbx) * ab->rh;
    double *sub = malloc(sizeof(double) * 3 * (size_t)ab->rw * ab->rh), *out = malloc(sizeof(double) * 2 * nv);
    if (!sub || !out) {
        free(sub), free(out);
        return CLI_EXIT_IO + 0 * cli_error(k_cmd, "out of memory");
    }
    for (int y = 0; y < ab->rh; ++y)
        memcpy(sub + 3 * (size_t)y * ab->rw, normals + 3 * ((size_t)(y0 + y) * W + x0), sizeof(double) * 3 * ab->rw);
    mf_status st = mf_prefilter_albedo_level(sub, ab->rw, ab->rh, o, ab->lr, out, msg, sizeof msg);
    free(sub);
    if (st != MF_OK) {
        free(out);
        int rc = cli_error(k_cmd, "%s: albedos of the block at texel (%d, %d), %d x %d: %s", input, x0, y0, ab->rw, ab->rh,
                           msg[0] ? msg : mf_status_str(st));
        return st == MF_ERR_DOMAIN ? rc : st == MF_ERR_ALLOC ? CLI_EXIT_IO : CLI_EXIT_FIT;
    }
    mf_io_atomic a;
    int ok = mf_io_atomic_begin(&a, path, msg, sizeof msg) == MF_OK;
    if (ok) {
        ok = fwrite(PF_ALB_MAGIC, 1, 8, a.file) == 8 && fwrite(out, sizeof(double), 2 * nv, a.file) == 2 * nv;
        if (!ok) {
            snprintf(msg, sizeof msg, "%.900s: write failed", path);
            mf_io_atomic_abort(&a);
        } else {
            ok = mf_io_atomic_commit(&a, msg, sizeof msg) == MF_OK;
        }
    }
    free(out);
    return ok ? 0 : cli_error(k_cmd, "%s", msg) * 0 + CLI_EXIT_IO;
}

/* Reads every block's albedo base into ab->alb.  Returns a CLI exit code, message printed. */
static int pf_read_base(const char *dir, size_t nv, pf_base *ab)
{
    long nb = (long)ab->nbx * ab->nby;
    ab->alb = malloc(sizeof(double) * 2 * nv * (size_t)nb);
    if (!ab->alb)
        return CLI_EXIT_IO + 0 * cli_error(k_cmd, "out of memory");
    for (long b = 0; b < nb; ++b) {
        char path[4400], magic[8];
        block_path(path, sizeof path, dir, b);
        FILE *f = fopen(path, "rb");
        int ok = f && fread(magic, 1, 8, f) == 8 && !memcmp(magic, PF_ALB_MAGIC, 8) &&
                 fread(ab->alb + 2 * nv * (size_t)b, sizeof(double), 2 * nv, f) == 2 * nv && fgetc(f) == EOF;
        if (f)
            fclose(f);
        if (!ok)
            return CLI_EXIT_IO + 0 * cli_error(k_cmd, "%s: %s", path, f ? "not an albedo work file of this run" : strerror(errno));
    }
    return 0;
}

/* Fits tile t and writes its file atomically; *reused gets the count of its lobes copied from identical
 * footprints (options.reuse).  Returns a CLI exit code (0 ok), message printed. */
static int pf_run_tile(const double *normals, int W, int H, const mf_prefilter_options *o, const pf_tile *t,
                       const pf_base *ab, const char *path, const char *input, long *reused)
{
    *reused = 0;
    char msg[1024];
    size_t nv = (size_t)o->n_theta * o->n_phi;
    double *sub = malloc(sizeof(double) * 3 * (size_t)t->w * t->h);
    /* a footprint tile: its blocks' albedo base (a whole number of blocks, cbx x cby) */
    int cbx = t->w / ab->rw, cby = t->h / ab->rh;
    int use = ab->alb && t->first > ab->lr && t->w % ab->rw == 0 && t->h % ab->rh == 0;
    double *base = use ? malloc(sizeof(double) * 2 * nv * (size_t)cbx * cby) : NULL;
    if (!sub || (use && !base)) {
        free(sub), free(base);
        return CLI_EXIT_IO + 0 * cli_error(k_cmd, "out of memory");
    }
    for (int y = 0; y < t->h; ++y)
        memcpy(sub + 3 * (size_t)y * t->w, normals + 3 * ((size_t)(t->y0 + y) * W + t->x0), sizeof(double) * 3 * t->w);
    for (int by = 0; use && by < cby; ++by)
        memcpy(base + 2 * nv * (size_t)by * cbx,
               ab->alb + 2 * nv * ((size_t)(t->y0 / ab->rh + by) * ab->nbx + (size_t)(t->x0 / ab->rw)),
               sizeof(double) * 2 * nv * (size_t)cbx);
    mf_prefilter_level *lv = NULL;
    int nl = 0;
    mf_status st = mf_prefilter_run_tile(sub, t->w, t->h, o, t->first, base, use ? ab->lr : 0, &lv, &nl, msg, sizeof msg);
    free(base);
    int nrec = t->last - t->first + 1;
    /* a region tile: the gate's reference R of its levels, computed here from its own normals (rank 0
     * reads it back instead of computing it: docs/prefilter.md, "The gate across ranks") */
    double *ref[16] = {NULL};
    mf_prefilter_gate_part part;
    if (st == MF_OK && t->first == 1) {
        for (int i = 0; i < nrec && st == MF_OK; ++i) {
            const mf_prefilter_level *L = &lv[i];
            ref[i] = malloc(sizeof(double) * MF_PREFILTER_GATE_NLIGHTS * (size_t)L->width * L->height * nv);
            st = ref[i] ? MF_OK : MF_ERR_ALLOC;
        }
        if (st == MF_OK && mf_prefilter_gate_reference(lv, nrec, sub, t->w, t->h, o, ref) != MF_OK)
            st = MF_ERR_INTERNAL, snprintf(msg, sizeof msg, "the gate's reference could not be computed");
        /* and its part of the gate: every check but its border's texel checks (rank 0's seams) */
        if (st == MF_OK && mf_prefilter_gate_region(lv, nrec, ref, W, H, t->x0, t->y0, t->w, t->h, o, &part) != MF_OK)
            st = MF_ERR_INTERNAL, snprintf(msg, sizeof msg, "the gate could not run on the tile");
    }
    free(sub);
    if (st != MF_OK) {
        for (int i = 0; i < nrec; ++i)
            free(ref[i]);
        mf_prefilter_levels_free(lv, nl);
        int rc = cli_error(k_cmd, "%s: tile at texel (%d, %d), %d x %d: %s", input, t->x0, t->y0, t->w, t->h,
                           msg[0] ? msg : mf_status_str(st));
        return st == MF_ERR_DOMAIN ? rc : st == MF_ERR_ALLOC ? CLI_EXIT_IO : CLI_EXIT_FIT;
    }
    pf_rec rec[16];
    int64_t off = 8 + 4 + (int64_t)sizeof(pf_rec) * nrec;
    for (int i = 0; i < nrec; ++i) {
        const mf_prefilter_level *L = &lv[t->first - 1 + i];
        size_t n = (size_t)L->width * L->height * nv;
        rec[i] = (pf_rec){L->level, L->width, L->height, L->not_converged, L->iterations, L->lobes, off,
                          off + (int64_t)(9 * n * sizeof(float)), off + (int64_t)(10 * n * sizeof(float)), 0, 0,
                          L->worst_residual, L->worst_albedo_err};
        off = rec[i].off_alb + (int64_t)(n * sizeof(float));
        if (ref[i]) {
            rec[i].off_ref = off;
            off += (int64_t)(MF_PREFILTER_GATE_NLIGHTS * pf_ref_kept(L->width, L->height, L->height) *
                             nv * sizeof(double));
        }
    }
    for (int i = 0; i < nrec && ref[0]; ++i) /* the part after the levels */
        rec[i].off_part = off;
    mf_io_atomic a;
    int ok = mf_io_atomic_begin(&a, path, msg, sizeof msg) == MF_OK;
    if (ok) {
        int32_t n32 = nrec;
        ok = fwrite(PF_TILE_MAGIC, 1, 8, a.file) == 8 && fwrite(&n32, 4, 1, a.file) == 1 &&
             fwrite(rec, sizeof(pf_rec), (size_t)nrec, a.file) == (size_t)nrec;
        for (int i = 0; i < nrec && ok; ++i) {
            const mf_prefilter_level *L = &lv[t->first - 1 + i];
            size_t n = (size_t)L->width * L->height * nv;
            ok = fwrite(L->m, sizeof(float), 9 * n, a.file) == 9 * n && fwrite(L->magnitude, sizeof(float), n, a.file) == n &&
                 fwrite(L->albedo, sizeof(float), n, a.file) == n;
            for (int y = 0; ok && ref[i] && y < L->height; ++y) { /* R where rank 0 reads it */
                int c[4], k = mf_prefilter_gate_ref_cols(L->width, L->height, y, c);
                for (int q = 0; q < k && ok; ++q) {
                    size_t cnt = MF_PREFILTER_GATE_NLIGHTS * (size_t)(c[2 * q + 1] - c[2 * q]) * nv;
                    ok = fwrite(ref[i] + MF_PREFILTER_GATE_NLIGHTS * ((size_t)y * L->width + c[2 * q]) * nv,
                                sizeof(double), cnt, a.file) == cnt;
                }
            }
        }
        if (ok && ref[0])
            ok = fwrite(&part, sizeof part, 1, a.file) == 1;
        if (!ok) {
            snprintf(msg, sizeof msg, "%.900s: write failed", path);
            mf_io_atomic_abort(&a);
        } else {
            ok = mf_io_atomic_commit(&a, msg, sizeof msg) == MF_OK;
        }
    }
    for (int i = 0; i < nrec; ++i)
        *reused += lv[t->first - 1 + i].reused;
    mf_prefilter_levels_free(lv, nl);
    for (int i = 0; i < nrec; ++i)
        free(ref[i]);
    return ok ? 0 : cli_error(k_cmd, "%s", msg) * 0 + CLI_EXIT_IO;
}

/* The tiles of this rank still to fit, shared by `workers` threads. */
typedef struct {
    const double *normals;
    int W, H;
    mf_prefilter_options o; /* o.threads: per tile */
    const pf_tile *tiles;
    const pf_base *ab; /* the albedo base; with blocks = 1, the queue's items are its blocks */
    int blocks;
    const char *dir, *input;
    long *todo, ntodo, next, max_tiles;
    long reused; /* lobes copied from identical footprints in the tiles fitted (options.reuse) */
    int rc, stopped;
    pthread_mutex_t lock;
} pf_queue;

/* Progress of the fits on a terminal (rank 0; --quiet: none): lobes stored by this process against
 * the lobes of the tiles it has to fit, at most twice a second. */
static int g_pf_quiet;
typedef struct {
    int show;
    const char *what;
    long total;
    _Atomic long done, last_ms;
    struct timespec t0;
} pf_progress;

static long pf_ms_since(const struct timespec *t0)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (long)(t.tv_sec - t0->tv_sec) * 1000 + (long)((t.tv_nsec - t0->tv_nsec) / 1000000);
}

static void pf_progress_cb(void *user, long n)
{
    pf_progress *p = user;
    long d = atomic_fetch_add(&p->done, n) + n, ms = pf_ms_since(&p->t0), last = atomic_load(&p->last_ms);
    if (ms - last < 500 || !atomic_compare_exchange_strong(&p->last_ms, &last, ms))
        return;
    double pct = p->total > 0 ? 100.0 * (double)d / (double)p->total : 100.0;
    fprintf(stderr, "\rmfkit prefilter: %s: %ld of %ld lobes (%.0f%%), %.0f s ", p->what, d, p->total,
            pct > 100.0 ? 100.0 : pct, 1e-3 * (double)ms);
}

/* The lobes of tile t: every level of it, nv views each (a level narrower than the tile's 2^l
 * texels holds one texel along that axis). */
static long pf_tile_lobes(const pf_tile *t, long nv)
{
    long n = 0;
    for (int l = t->first; l <= t->last; ++l)
        n += (long)((t->w >> l) > 0 ? t->w >> l : 1) * ((t->h >> l) > 0 ? t->h >> l : 1) * nv;
    return n;
}

static void *pf_worker(void *arg)
{
    pf_queue *q = arg;
    for (;;) {
        long k = -1;
        pthread_mutex_lock(&q->lock);
        if (!q->rc && !q->stopped && q->next < q->ntodo) {
            if (g_pf_cancel)
                q->stopped = CLI_EXIT_INTERRUPTED;
            else if (q->max_tiles >= 0 && q->next >= q->max_tiles)
                q->stopped = PF_EXIT_INCOMPLETE;
            else
                k = q->todo[q->next++];
        }
        pthread_mutex_unlock(&q->lock);
        if (k < 0)
            return NULL;
        char path[4400];
        if (q->blocks)
            block_path(path, sizeof path, q->dir, k);
        else
            tile_path(path, sizeof path, q->dir, k);
        long reused = 0;
        int r = q->blocks ? pf_run_block(q->normals, q->W, &q->o, q->ab, k, path, q->input)
                          : pf_run_tile(q->normals, q->W, q->H, &q->o, &q->tiles[k], q->ab, path, q->input, &reused);
        pthread_mutex_lock(&q->lock);
        if (r && !q->rc)
            q->rc = r;
        q->reused += reused;
        pthread_mutex_unlock(&q->lock);
    }
}

static void pf_run_queue(pf_queue *q, int workers)
{
    pthread_t th[256];
    int started = 0;
    pthread_mutex_init(&q->lock, NULL);
    for (; started < workers - 1; ++started)
        if (pthread_create(&th[started], NULL, pf_worker, q) != 0)
            break;
    pf_worker(q);
    for (int i = 0; i < started; ++i)
        pthread_join(th[i], NULL);
    pthread_mutex_destroy(&q->lock);
}

/* ---- streaming writers --------------------------------------------------------------------------- */

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

static void put_i32(mf_buf *b, int32_t v) { mf_buf_u32le(b, (uint32_t)v); }
static void put_attr(mf_buf *b, const char *name, const char *type, int32_t size)
{
    mf_buf_put(b, name, strlen(name) + 1);
    mf_buf_put(b, type, strlen(type) + 1);
    put_i32(b, size);
}

/* An uncompressed scanline OpenEXR file, RGBA float32, width x height, written by chunks in any
 * order (each chunk's offset is known in advance): the header and the offset table here. */
static void exr_header(mf_buf *b, int width, int height, int64_t *data_start)
{
    static const unsigned char magic[4] = {0x76, 0x2f, 0x31, 0x01};
    mf_buf_put(b, magic, 4);
    put_i32(b, 2); /* version 2, scanline, short names */
    put_attr(b, "channels", "chlist", 4 * 18 + 1);
    for (const char *c = "ABGR"; *c; ++c) { /* alphabetical, as the format stores them */
        mf_buf_put(b, c, 1);
        mf_buf_put(b, "", 1);
        put_i32(b, 2);                     /* FLOAT */
        mf_buf_put(b, "\0\0\0\0", 4);      /* pLinear, reserved */
        put_i32(b, 1), put_i32(b, 1);      /* sampling */
    }
    mf_buf_put(b, "", 1);
    put_attr(b, "compression", "compression", 1);
    mf_buf_put(b, "", 1); /* NO_COMPRESSION */
    for (int w = 0; w < 2; ++w) {
        put_attr(b, w ? "displayWindow" : "dataWindow", "box2i", 16);
        put_i32(b, 0), put_i32(b, 0), put_i32(b, width - 1), put_i32(b, height - 1);
    }
    put_attr(b, "lineOrder", "lineOrder", 1);
    mf_buf_put(b, "", 1);
    put_attr(b, "pixelAspectRatio", "float", 4);
    mf_buf_f32le(b, 1.0f);
    put_attr(b, "screenWindowCenter", "v2f", 8);
    mf_buf_f32le(b, 0.0f), mf_buf_f32le(b, 0.0f);
    put_attr(b, "screenWindowWidth", "float", 4);
    mf_buf_f32le(b, 1.0f);
    mf_buf_put(b, "", 1);
    int64_t start = (int64_t)b->len + 8 * (int64_t)height, chunk = 8 + 16 * (int64_t)width;
    for (int y = 0; y < height; ++y) {
        uint64_t v = (uint64_t)(start + y * chunk);
        mf_buf_u32le(b, (uint32_t)v), mf_buf_u32le(b, (uint32_t)(v >> 32));
    }
    *data_start = start;
}

/* ---- assembly (rank 0) --------------------------------------------------------------------------- */

typedef struct {
    long lobes, iterations;
    int not_converged;
    double worst_residual, worst_albedo_err;
    long nonfinite, magnitude_neg;
    double mag_min, mag_max;
} pf_stats;

typedef struct {
    const char *dir, *input;
    int W, H, nl, T;
    const mf_prefilter_options *o;
    const pf_plan *plans;
    long ntiles;
    int ranks, lambert, force;
    const double *normals; /* the map, for the gate's reference */
    const char *pair;      /* --lobes 2, half b: half a's table directory, whose checkpoint holds its tiles (the
                              two-lobe gate, pf_assemble); NULL otherwise */
} pf_assembly;

/* The two-lobe gate's result (--lobes 2): set by half b's assembly (rank 0), written into both halves'
 * manifests (half a is assembled after it) */
static mf_prefilter_gate g_pf_pair;
static int g_pf_pair_ran;

static int pf_open_tile(const char *dir, long k, int rec, FILE **f, pf_rec *r, char *msg, size_t msg_size)
{
    char path[4096], magic[8];
    int32_t n = 0;
    tile_path(path, sizeof path, dir, k);
    *f = fopen(path, "rb");
    if (!*f || fread(magic, 1, 8, *f) != 8 || memcmp(magic, PF_TILE_MAGIC, 8) || fread(&n, 4, 1, *f) != 1 ||
        rec >= n || fseek(*f, (long)(12 + sizeof(pf_rec) * (size_t)rec), SEEK_SET) || fread(r, sizeof *r, 1, *f) != 1) {
        snprintf(msg, msg_size, "%.900s: %s", path, *f ? "not a tile of this run (truncated or corrupt)" : strerror(errno));
        if (*f)
            fclose(*f), *f = NULL;
        return 0;
    }
    return 1;
}

static const char *const k_lookup_doc =
    "textures t0, t1, t2: 2D array textures, layer i_theta * N_PHI + i_phi, MIP level k - 1 = prefilter\n"
    " * level k (from prefilter_mip<k>_<t>.exr: the tile of view (i_theta, i_phi) at column i_phi * w_k,\n"
    " * row i_theta * h_k), filter LINEAR_MIPMAP_LINEAR, wrap REPEAT.  t0 = (M00, M01, M02, M10),\n"
    " * t1 = (M11, M12, M20, M21), t2 = (M22, magnitude, 0, 0); M the forward LTC in the view-azimuth-\n"
    " * aligned frame (rotate the polygon by -phi about the normal, then apply inverse(M)), uv the map's\n"
    " * texture coordinate, lod the map's level of detail (>= 1; below, shade with the base LTC table),\n"
    " * theta, phi the view's elevation and azimuth in the tangent frame (radians).";

static const char *const k_tap_doc =
    "mfpfLookupTap: the filter of mfpfLookup split into its eight texel taps (tap k = 0..7: MIP level\n"
    " * (k >> 2) of the two around lod - 1, corner (k & 1, (k >> 1) & 1) of the bilinear footprint;\n"
    " * the four views blended as in mfpfLookup); returns the tap's weight (the eight sum to 1) and its\n"
    " * M and magnitude.  Shade each tap's lobe and sum weight * magnitude * integral: neighbouring texels\n"
    " * whose lobes reflect different facets then give the mean of their highlights, where mfpfLookup's\n"
    " * blended M gives one lobe between them.  Eight LTC integrals per pixel instead of one; skip taps of\n"
    " * weight 0.  The same textures; texelFetch, so no sampler.";

static void write_glsl(mf_buf *b, const mf_prefilter_options *o)
{
    mf_buf_printf(b,
        "// mfkit prefilter lookup (GLSL 4.50), generated by `mfkit prefilter`; docs/prefilter.md.\n"
        "/* %s */\n"
        "const int MFPF_N_THETA = %d;\nconst int MFPF_N_PHI = %d;\nconst float MFPF_THETA_MAX = %.9g;\n"
        "void mfpfLookup(sampler2DArray t0, sampler2DArray t1, sampler2DArray t2, vec2 uv, float lod, float theta,\n"
        "                float phi, out mat3 M, out float magnitude)\n"
        "{\n"
        "    float ft = clamp(theta / MFPF_THETA_MAX, 0.0, 1.0) * float(MFPF_N_THETA - 1);\n"
        "    int i0 = min(int(ft), MFPF_N_THETA - 2);\n"
        "    float wt = ft - float(i0);\n"
        "    float fp = phi * (float(MFPF_N_PHI) / 6.28318530717958648);\n"
        "    fp -= float(MFPF_N_PHI) * floor(fp / float(MFPF_N_PHI));\n"
        "    int j0 = min(int(fp), MFPF_N_PHI - 1);\n"
        "    float wp = fp - float(j0);\n"
        "    int j1 = (j0 + 1) %% MFPF_N_PHI;\n"
        "    float l = max(lod - 1.0, 0.0);\n"
        "    vec4 a = vec4(0.0), b = vec4(0.0), c = vec4(0.0);\n"
        "    for (int k = 0; k < 4; ++k) {\n"
        "        int di = k & 1, dj = k >> 1;\n"
        "        float w = (di == 1 ? wt : 1.0 - wt) * (dj == 1 ? wp : 1.0 - wp);\n"
        "        vec3 s = vec3(uv, float((i0 + di) * MFPF_N_PHI + (dj == 1 ? j1 : j0)));\n"
        "        a += w * textureLod(t0, s, l);\n"
        "        b += w * textureLod(t1, s, l);\n"
        "        c += w * textureLod(t2, s, l);\n"
        "    }\n"
        "    M = mat3(a.x, a.w, b.z, a.y, b.x, b.w, a.z, b.y, c.x); // columns of the row-major M\n"
        "    magnitude = c.y;\n"
        "}\n"
        "/* %s */\n"
        "float mfpfLookupTap(sampler2DArray t0, sampler2DArray t1, sampler2DArray t2, int k, vec2 uv, float lod,\n"
        "                    float theta, float phi, out mat3 M, out float magnitude)\n"
        "{\n"
        "    float ft = clamp(theta / MFPF_THETA_MAX, 0.0, 1.0) * float(MFPF_N_THETA - 1);\n"
        "    int i0 = min(int(ft), MFPF_N_THETA - 2);\n"
        "    float wt = ft - float(i0);\n"
        "    float fp = phi * (float(MFPF_N_PHI) / 6.28318530717958648);\n"
        "    fp -= float(MFPF_N_PHI) * floor(fp / float(MFPF_N_PHI));\n"
        "    int j0 = min(int(fp), MFPF_N_PHI - 1);\n"
        "    float wp = fp - float(j0);\n"
        "    int j1 = (j0 + 1) %% MFPF_N_PHI;\n"
        "    int nl = textureQueryLevels(t0);\n"
        "    float l = min(max(lod - 1.0, 0.0), float(nl - 1));\n"
        "    int l0 = int(floor(l)), il = k >> 2, lv = min(l0 + il, nl - 1);\n"
        "    ivec2 size = textureSize(t0, lv).xy;\n"
        "    vec2 f = uv * vec2(size) - 0.5, f0 = floor(f), fr = f - f0;\n"
        "    int ix = k & 1, iy = (k >> 1) & 1;\n"
        "    ivec2 xy = (ivec2(f0 - vec2(size) * floor(f0 / vec2(size))) + ivec2(ix, iy)) %% size;\n"
        "    float weight = (il == 1 ? l - float(l0) : 1.0 - (l - float(l0))) * (ix == 1 ? fr.x : 1.0 - fr.x)\n"
        "                 * (iy == 1 ? fr.y : 1.0 - fr.y);\n"
        "    vec4 a = vec4(0.0), b = vec4(0.0), c = vec4(0.0);\n"
        "    for (int q = 0; q < 4; ++q) {\n"
        "        int di = q & 1, dj = q >> 1;\n"
        "        float w = (di == 1 ? wt : 1.0 - wt) * (dj == 1 ? wp : 1.0 - wp);\n"
        "        ivec3 s = ivec3(xy, (i0 + di) * MFPF_N_PHI + (dj == 1 ? j1 : j0));\n"
        "        a += w * texelFetch(t0, s, lv);\n"
        "        b += w * texelFetch(t1, s, lv);\n"
        "        c += w * texelFetch(t2, s, lv);\n"
        "    }\n"
        "    M = mat3(a.x, a.w, b.z, a.y, b.x, b.w, a.z, b.y, c.x);\n"
        "    magnitude = c.y;\n"
        "    return weight;\n"
        "}\n",
        k_lookup_doc, o->n_theta, o->n_phi, MF_PREFILTER_THETA_MAX, k_tap_doc);
}

static void write_hlsl(mf_buf *b, const mf_prefilter_options *o)
{
    mf_buf_printf(b,
        "// mfkit prefilter lookup (HLSL, shader model 5), generated by `mfkit prefilter`; docs/prefilter.md.\n"
        "/* %s */\n"
        "static const int MFPF_N_THETA = %d;\nstatic const int MFPF_N_PHI = %d;\nstatic const float MFPF_THETA_MAX = %.9g;\n"
        "void mfpfLookup(Texture2DArray t0, Texture2DArray t1, Texture2DArray t2, SamplerState s, float2 uv, float lod,\n"
        "                float theta, float phi, out float3x3 M, out float magnitude)\n"
        "{\n"
        "    float ft = clamp(theta / MFPF_THETA_MAX, 0.0, 1.0) * float(MFPF_N_THETA - 1);\n"
        "    int i0 = min(int(ft), MFPF_N_THETA - 2);\n"
        "    float wt = ft - float(i0);\n"
        "    float fp = phi * (float(MFPF_N_PHI) / 6.28318530717958648);\n"
        "    fp -= float(MFPF_N_PHI) * floor(fp / float(MFPF_N_PHI));\n"
        "    int j0 = min(int(fp), MFPF_N_PHI - 1);\n"
        "    float wp = fp - float(j0);\n"
        "    int j1 = (j0 + 1) %% MFPF_N_PHI;\n"
        "    float l = max(lod - 1.0, 0.0);\n"
        "    float4 a = 0.0, b = 0.0, c = 0.0;\n"
        "    for (int k = 0; k < 4; ++k) {\n"
        "        int di = k & 1, dj = k >> 1;\n"
        "        float w = (di == 1 ? wt : 1.0 - wt) * (dj == 1 ? wp : 1.0 - wp);\n"
        "        float3 p = float3(uv, float((i0 + di) * MFPF_N_PHI + (dj == 1 ? j1 : j0)));\n"
        "        a += w * t0.SampleLevel(s, p, l);\n"
        "        b += w * t1.SampleLevel(s, p, l);\n"
        "        c += w * t2.SampleLevel(s, p, l);\n"
        "    }\n"
        "    M = float3x3(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, c.x); // rows of M\n"
        "    magnitude = c.y;\n"
        "}\n"
        "/* %s */\n"
        "float mfpfLookupTap(Texture2DArray t0, Texture2DArray t1, Texture2DArray t2, int k, float2 uv, float lod,\n"
        "                    float theta, float phi, out float3x3 M, out float magnitude)\n"
        "{\n"
        "    float ft = clamp(theta / MFPF_THETA_MAX, 0.0, 1.0) * float(MFPF_N_THETA - 1);\n"
        "    int i0 = min(int(ft), MFPF_N_THETA - 2);\n"
        "    float wt = ft - float(i0);\n"
        "    float fp = phi * (float(MFPF_N_PHI) / 6.28318530717958648);\n"
        "    fp -= float(MFPF_N_PHI) * floor(fp / float(MFPF_N_PHI));\n"
        "    int j0 = min(int(fp), MFPF_N_PHI - 1);\n"
        "    float wp = fp - float(j0);\n"
        "    int j1 = (j0 + 1) %% MFPF_N_PHI;\n"
        "    uint w0, h0, el, nl;\n"
        "    t0.GetDimensions(0, w0, h0, el, nl);\n"
        "    float l = min(max(lod - 1.0, 0.0), float(nl) - 1.0);\n"
        "    int l0 = int(floor(l)), il = k >> 2, lv = min(l0 + il, int(nl) - 1);\n"
        "    int2 size = int2(max(int(w0) >> lv, 1), max(int(h0) >> lv, 1));\n"
        "    float2 f = uv * float2(size) - 0.5, f0 = floor(f), fr = f - f0;\n"
        "    int ix = k & 1, iy = (k >> 1) & 1;\n"
        "    int2 xy = (int2(f0 - float2(size) * floor(f0 / float2(size))) + int2(ix, iy)) %% size;\n"
        "    float weight = (il == 1 ? l - float(l0) : 1.0 - (l - float(l0))) * (ix == 1 ? fr.x : 1.0 - fr.x)\n"
        "                 * (iy == 1 ? fr.y : 1.0 - fr.y);\n"
        "    float4 a = 0.0, b = 0.0, c = 0.0;\n"
        "    for (int q = 0; q < 4; ++q) {\n"
        "        int di = q & 1, dj = q >> 1;\n"
        "        float w = (di == 1 ? wt : 1.0 - wt) * (dj == 1 ? wp : 1.0 - wp);\n"
        "        int4 p = int4(xy, (i0 + di) * MFPF_N_PHI + (dj == 1 ? j1 : j0), lv);\n"
        "        a += w * t0.Load(p);\n"
        "        b += w * t1.Load(p);\n"
        "        c += w * t2.Load(p);\n"
        "    }\n"
        "    M = float3x3(a.x, a.y, a.z, a.w, b.x, b.y, b.z, b.w, c.x);\n"
        "    magnitude = c.y;\n"
        "    return weight;\n"
        "}\n",
        k_lookup_doc, o->n_theta, o->n_phi, MF_PREFILTER_THETA_MAX, k_tap_doc);
}

static int begin_file(mf_io_atomic *files, int *nf, const char *dir, const char *name, char *msg, size_t msg_size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (mf_io_atomic_begin(&files[*nf], path, msg, msg_size) != MF_OK)
        return 0;
    ++*nf;
    return 1;
}

static int put_file(FILE *f, const mf_buf *b) { return !b->failed && fwrite(b->data, 1, b->len, f) == b->len; }

/* One level being assembled: its files, its band of tile files, its row buffers. */
typedef struct {
    int f0;           /* its first file in files[]: ltc, magnitude, albedo .npy, then the 3 EXR */
    int64_t exr_data; /* the EXR files' first chunk */
    FILE **tf;        /* the open tiles of the current band */
    pf_rec *recs;
    float *rm, *ra, *rb; /* one row: matrices, magnitudes, albedos */
    double *rr;          /* a region level's row of the gate's reference R, from its tiles (NULL: the gate computes it) */
    FILE **pt;           /* --lobes 2, half b: half a's open tiles of the band, their records, its row, the pair's row */
    pf_rec *precs;
    float *pm, *pa, *pb, *qm, *qa, *qb;
} pf_lvasm;

/* Row rr of a tile (seg entries) from its open file: matrices, magnitudes, albedos. */
static int pf_read_tile_row(FILE *f, const pf_rec *rec, int rr, size_t seg, float *rm, float *ra, float *rb)
{
    return fseek(f, (long)(rec->off_m + (int64_t)(rr * seg * 9 * sizeof(float))), SEEK_SET) == 0 &&
           fread(rm, sizeof(float), 9 * seg, f) == 9 * seg &&
           fseek(f, (long)(rec->off_mag + (int64_t)(rr * seg * sizeof(float))), SEEK_SET) == 0 &&
           fread(ra, sizeof(float), seg, f) == seg &&
           fseek(f, (long)(rec->off_alb + (int64_t)(rr * seg * sizeof(float))), SEEK_SET) == 0 &&
           fread(rb, sizeof(float), seg, f) == seg;
}

/* --lobes 2: half a's row r of level P, read from its checkpoint's tiles (the same plan: the same map,
 * tile size and views), for the two-lobe gate.  pt: the band's open tiles (opened at the band's first
 * row, closed at the level's last), precs their records. */
static int pf_pair_row(const char *pair, const pf_plan *P, int nv, int r, FILE **pt, pf_rec *precs, float *pm,
                       float *pa, float *pb, char *msg, size_t msz)
{
    int gy = r / P->th, rr = r % P->th, ok = 1;
    if (rr == 0) {
        for (int gx = 0; gx < P->nx; ++gx)
            if (pt[gx])
                fclose(pt[gx]), pt[gx] = NULL;
        for (int gx = 0; gx < P->nx && ok; ++gx) {
            long k = P->base + (long)gy * P->nx + gx;
            ok = pf_open_tile(pair, k, P->rec, &pt[gx], &precs[gx], msg, msz);
            if (ok && (precs[gx].level != P->level || precs[gx].w != P->tw || precs[gx].h != P->th))
                ok = 0, snprintf(msg, msz, "%.900s/" PF_WORK ": tile %ld does not hold level %d", pair, k, P->level);
        }
    }
    size_t seg = (size_t)P->tw * nv;
    for (int gx = 0; gx < P->nx && ok; ++gx)
        if (!(ok = pf_read_tile_row(pt[gx], &precs[gx], rr, seg, pm + gx * seg * 9, pa + gx * seg, pb + gx * seg)))
            snprintf(msg, msz, "%.900s/" PF_WORK ": tile %ld truncated", pair, P->base + (long)gy * P->nx + gx);
    if (r == P->h - 1)
        for (int gx = 0; gx < P->nx; ++gx)
            if (pt[gx])
                fclose(pt[gx]), pt[gx] = NULL;
    return ok;
}

/* Streams the levels from the tile files row by row, in the gate's order (level l's row r right after
 * rows 2r, 2r + 1 of level l - 1: mf_prefilter_gate_stream_next), into the output files and the
 * gate, which holds a few rows per level; writes the manifest and snippets, commits all. */
static int pf_assemble(const pf_assembly *A, double secs, long resumed, long reused)
{
    const mf_prefilter_options *o = A->o;
    const char *dir = A->dir;
    const int nv = o->n_theta * o->n_phi, nl = A->nl;
    struct timespec w0, c0; /* the assembly's and gate's wall and process CPU, for the summary */
    clock_gettime(CLOCK_MONOTONIC, &w0);
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c0);
    char msg[1024] = "";
    int nfiles_max = 6 * nl + 3, nf = 0, ok = 1;
    mf_io_atomic *files = calloc((size_t)nfiles_max, sizeof *files);
    pf_stats *stats = calloc((size_t)nl, sizeof *stats);
    mf_prefilter_level *gl = calloc((size_t)nl, sizeof *gl); /* the levels' shapes, for the gate */
    pf_lvasm *LA = calloc((size_t)nl, sizeof *LA);
    mf_prefilter_gate_stream *gs = NULL;
    mf_buf b = {0};
    if (!files || !stats || !gl || !LA)
        ok = 0, snprintf(msg, sizeof msg, "out of memory");
    /* every level's files and headers */
    for (int li = 0; li < nl && ok; ++li) {
        const pf_plan *P = &A->plans[li];
        pf_stats *S = &stats[li];
        pf_lvasm *V = &LA[li];
        S->mag_min = INFINITY, S->mag_max = -INFINITY;
        char name[64], shape[128];
        int f0 = V->f0 = nf;
        snprintf(name, sizeof name, "ltc_mip%d.npy", P->level);
        ok = begin_file(files, &nf, dir, name, msg, sizeof msg);
        snprintf(name, sizeof name, "magnitude_mip%d.npy", P->level);
        ok = ok && begin_file(files, &nf, dir, name, msg, sizeof msg);
        snprintf(name, sizeof name, "albedo_mip%d.npy", P->level);
        ok = ok && begin_file(files, &nf, dir, name, msg, sizeof msg);
        for (int t = 0; t < 3 && ok; ++t) {
            snprintf(name, sizeof name, "prefilter_mip%d_%d.exr", P->level, t);
            ok = begin_file(files, &nf, dir, name, msg, sizeof msg);
        }
        if (!ok)
            break;
        const int aw = P->w * o->n_phi, ah = P->h * o->n_theta;
        b.len = 0;
        snprintf(shape, sizeof shape, "(%d, %d, %d, %d, 3, 3)", P->h, P->w, o->n_theta, o->n_phi);
        npy_header(&b, shape);
        ok = put_file(files[f0].file, &b);
        b.len = 0;
        snprintf(shape, sizeof shape, "(%d, %d, %d, %d)", P->h, P->w, o->n_theta, o->n_phi);
        npy_header(&b, shape);
        ok = ok && put_file(files[f0 + 1].file, &b) && put_file(files[f0 + 2].file, &b);
        b.len = 0;
        exr_header(&b, aw, ah, &V->exr_data);
        for (int t = 0; t < 3 && ok; ++t)
            ok = put_file(files[f0 + 3 + t].file, &b);
        if (!ok) {
            snprintf(msg, sizeof msg, "%.900s: write failed", files[f0].path);
            break;
        }
        size_t row = (size_t)P->w * nv;
        V->rm = malloc(sizeof(float) * 9 * row);
        V->ra = malloc(sizeof(float) * row);
        V->rb = malloc(sizeof(float) * row);
        V->tf = calloc((size_t)P->nx, sizeof *V->tf);
        V->recs = malloc(sizeof(pf_rec) * (size_t)P->nx);
        if (P->base == 0) /* region tiles (numbered from 0) carry R; footprint tiles do not */
            V->rr = malloc(sizeof(double) * MF_PREFILTER_GATE_NLIGHTS * row);
        if (!V->rm || !V->ra || !V->rb || !V->tf || !V->recs || (P->base == 0 && !V->rr)) {
            ok = 0, snprintf(msg, sizeof msg, "out of memory");
            break;
        }
        if (A->pair) {
            V->pt = calloc((size_t)P->nx, sizeof *V->pt);
            V->precs = malloc(sizeof(pf_rec) * (size_t)P->nx);
            V->pm = malloc(sizeof(float) * 9 * row), V->pa = malloc(sizeof(float) * row);
            V->pb = malloc(sizeof(float) * row), V->qm = malloc(sizeof(float) * 18 * row);
            V->qa = malloc(sizeof(float) * 2 * row), V->qb = malloc(sizeof(float) * row);
            if (!V->pt || !V->precs || !V->pm || !V->pa || !V->pb || !V->qm || !V->qa || !V->qb) {
                ok = 0, snprintf(msg, sizeof msg, "out of memory");
                break;
            }
        }
        gl[li] = (mf_prefilter_level){.level = P->level, .width = P->w, .height = P->h, .n_theta = o->n_theta,
                                      .n_phi = o->n_phi};
    }
    /* the library's gate, with the reference (mf_prefilter_gate_run_ref's result, streamed) */
    mf_prefilter_gate g;
    mf_prefilter_gate_bounds_default(&g);
    /* the region tiles gated themselves but for their borders (their parts, merged below as their
     * level-1 band opens): the stream runs the seams and the levels above */
    int nreg = 0;
    while (nreg < nl && A->plans[nreg].base == 0)
        ++nreg;
    if (ok && mf_prefilter_gate_stream_begin_regions(gl, nl, A->normals, A->W, A->H, A->W < A->T ? A->W : A->T,
                                                     A->H < A->T ? A->H : A->T, nreg, o, &g, &gs) != MF_OK)
        ok = 0, snprintf(msg, sizeof msg, "the gate could not run (out of memory, or no region tiles)");
    /* --lobes 2, half b: the two-lobe gate, on the sum of half a's lobes (read from its checkpoint) and
     * this half's: a whole stream (it computes its reference), fed the same rows in the same order */
    mf_prefilter_gate g2;
    mf_prefilter_gate_bounds_default(&g2);
    mf_prefilter_gate_stream *gs2 = NULL;
    mf_prefilter_options o2 = *o;
    o2.lobe = 0;
    if (ok && A->pair &&
        (mf_prefilter_gate_stream_begin(gl, nl, A->normals, A->W, A->H, &o2, &g2, &gs2) != MF_OK ||
         mf_prefilter_gate_stream_set_lobes(gs2, 2) != MF_OK))
        ok = 0, snprintf(msg, sizeof msg, "the two-lobe gate could not run (out of memory)");
    int lvi, r;
    while (ok && mf_prefilter_gate_stream_next(gs, &lvi, &r)) {
        const pf_plan *P = &A->plans[lvi];
        pf_stats *S = &stats[lvi];
        pf_lvasm *V = &LA[lvi];
        const int f0 = V->f0, aw = P->w * o->n_phi;
        const size_t row = (size_t)P->w * nv;
        float *rm = V->rm, *ra = V->ra, *rb = V->rb;
        FILE **tf = V->tf;
        pf_rec *recs = V->recs;
        int gy = r / P->th, rr = r % P->th;
        if (rr == 0) { /* the next band of tiles */
            for (int gx = 0; gx < P->nx; ++gx)
                if (tf[gx])
                    fclose(tf[gx]), tf[gx] = NULL;
            for (int gx = 0; gx < P->nx && ok; ++gx) {
                long k = P->base + (long)gy * P->nx + gx;
                ok = pf_open_tile(dir, k, P->rec, &tf[gx], &recs[gx], msg, sizeof msg);
                if (ok && (recs[gx].level != P->level || recs[gx].w != P->tw || recs[gx].h != P->th ||
                           (V->rr != NULL) != (recs[gx].off_ref > 0) || (V->rr != NULL) != (recs[gx].off_part > 0)))
                    ok = 0, snprintf(msg, sizeof msg, "%s/" PF_WORK ": tile %ld does not hold level %d", dir, k, P->level);
                if (ok && V->rr && lvi == 0) { /* a region tile's first band: its part of the gate */
                    mf_prefilter_gate_part part;
                    ok = fseek(tf[gx], (long)recs[gx].off_part, SEEK_SET) == 0 && fread(&part, sizeof part, 1, tf[gx]) == 1 &&
                         mf_prefilter_gate_stream_merge(gs, &part) == MF_OK;
                    if (!ok)
                        snprintf(msg, sizeof msg, "%s/" PF_WORK ": tile %ld truncated", dir, k);
                }
                if (ok) {
                    S->lobes += recs[gx].lobes, S->iterations += recs[gx].iterations;
                    S->not_converged += recs[gx].not_converged;
                    S->worst_residual = fmax(S->worst_residual, recs[gx].worst_residual);
                    S->worst_albedo_err = fmax(S->worst_albedo_err, recs[gx].worst_albedo_err);
                }
            }
        }
        size_t seg = (size_t)P->tw * nv;
        for (int gx = 0; gx < P->nx && ok; ++gx) {
            FILE *f = tf[gx];
            ok = pf_read_tile_row(f, &recs[gx], rr, seg, rm + gx * seg * 9, ra + gx * seg, rb + gx * seg);
            const size_t nref = MF_PREFILTER_GATE_NLIGHTS * seg;
            if (ok && V->rr) { /* the kept entries of the row (pf_ref_kept); the others NaN, never read */
                double *dst = V->rr + gx * nref;
                int c[4], k = mf_prefilter_gate_ref_cols(P->tw, P->th, rr, c);
                for (size_t i = 0; i < nref; ++i)
                    dst[i] = NAN;
                ok = fseek(f, (long)(recs[gx].off_ref + (int64_t)(MF_PREFILTER_GATE_NLIGHTS *
                                                                  pf_ref_kept(P->tw, P->th, rr) * nv *
                                                                  sizeof(double))),
                           SEEK_SET) == 0;
                for (int q = 0; q < k && ok; ++q) {
                    size_t cnt = MF_PREFILTER_GATE_NLIGHTS * (size_t)(c[2 * q + 1] - c[2 * q]) * nv;
                    ok = fread(dst + MF_PREFILTER_GATE_NLIGHTS * (size_t)c[2 * q] * nv, sizeof(double), cnt, f) == cnt;
                }
            }
            if (!ok)
                snprintf(msg, sizeof msg, "%s/" PF_WORK ": tile %ld truncated", dir, P->base + (long)gy * P->nx + gx);
        }
        if (!ok)
            break;
        /* the row to the gate, counts, then to the files */
        if (mf_prefilter_gate_stream_row_ref(gs, lvi, r, rm, ra, rb, V->rr) != MF_OK) {
            ok = 0, snprintf(msg, sizeof msg, "the gate could not run (rows out of order)");
            break;
        }
        if (A->pair) {
            if (!pf_pair_row(A->pair, P, nv, r, V->pt, V->precs, V->pm, V->pa, V->pb, msg, sizeof msg))
                ok = 0;
            else {
                mf_prefilter_gate_pair_row(V->pm, V->pa, V->pb, rm, ra, rb, row, V->qm, V->qa, V->qb);
                if (mf_prefilter_gate_stream_row(gs2, lvi, r, V->qm, V->qa, V->qb) != MF_OK)
                    ok = 0, snprintf(msg, sizeof msg, "the two-lobe gate could not run (rows out of order)");
            }
            if (!ok)
                break;
        }
        for (size_t i = 0; i < 9 * row; ++i)
            S->nonfinite += !isfinite(rm[i]);
        for (size_t i = 0; i < row; ++i) {
            S->nonfinite += !isfinite(ra[i]) + !isfinite(rb[i]);
            S->magnitude_neg += !(ra[i] >= 0.0f && rb[i] >= 0.0f);
            S->mag_min = fmin(S->mag_min, ra[i]), S->mag_max = fmax(S->mag_max, ra[i]);
        }
        b.len = 0;
        for (size_t i = 0; i < 9 * row; ++i)
            mf_buf_f32le(&b, rm[i]);
        ok = put_file(files[f0].file, &b);
        b.len = 0;
        for (size_t i = 0; i < row; ++i)
            mf_buf_f32le(&b, ra[i]);
        ok = ok && put_file(files[f0 + 1].file, &b);
        b.len = 0;
        for (size_t i = 0; i < row; ++i)
            mf_buf_f32le(&b, rb[i]);
        ok = ok && put_file(files[f0 + 2].file, &b);
        /* EXR rows y = i_theta * h + r: x = i_phi * w + column; channels A, B, G, R planes */
        for (int t = 0; t < 3 && ok; ++t) {
            FILE *f = files[f0 + 3 + t].file;
            for (int a = 0; a < o->n_theta && ok; ++a) {
                int y = a * P->h + r;
                b.len = 0;
                put_i32(&b, y);
                put_i32(&b, 16 * aw);
                for (int ch = 3; ch >= 0; --ch) { /* A B G R */
                    int q = 4 * t + ch;
                    for (int p = 0; p < o->n_phi; ++p)
                        for (int c = 0; c < P->w; ++c) {
                            size_t idx = ((size_t)c * o->n_theta + a) * o->n_phi + p;
                            float v = q < 9 ? rm[9 * idx + q] : q == 9 ? ra[idx] : 0.0f;
                            mf_buf_f32le(&b, v);
                        }
                }
                ok = fseek(f, (long)(V->exr_data + (int64_t)y * (8 + 16 * (int64_t)aw)), SEEK_SET) == 0 && put_file(f, &b);
            }
        }
        if (!ok && !msg[0])
            snprintf(msg, sizeof msg, "%.900s: write failed", files[f0].path);
        if (r == P->h - 1) /* the level's last row: its buffers and tiles go */
            for (int gx = 0; gx < P->nx; ++gx)
                if (tf[gx])
                    fclose(tf[gx]), tf[gx] = NULL;
    }
    if (ok) {
        mf_status gst = mf_prefilter_gate_stream_end(gs);
        gs = NULL;
        if (gst != MF_OK)
            ok = 0, snprintf(msg, sizeof msg, "the gate could not run (rows missing)");
    }
    mf_prefilter_gate_stream_free(gs);
    if (ok && gs2) {
        mf_status gst = mf_prefilter_gate_stream_end(gs2);
        gs2 = NULL;
        if (gst != MF_OK)
            ok = 0, snprintf(msg, sizeof msg, "the two-lobe gate could not run (rows missing)");
        g_pf_pair = g2, g_pf_pair_ran = 1;
    }
    mf_prefilter_gate_stream_free(gs2);
    for (int l = 0; LA && l < nl; ++l) {
        for (int gx = 0; LA[l].pt && gx < A->plans[l].nx; ++gx)
            if (LA[l].pt[gx])
                fclose(LA[l].pt[gx]);
        free(LA[l].pt), free(LA[l].precs), free(LA[l].pm), free(LA[l].pa), free(LA[l].pb);
        free(LA[l].qm), free(LA[l].qa), free(LA[l].qb);
    }
    for (int l = 0; LA && l < nl; ++l) {
        for (int gx = 0; LA[l].tf && gx < A->plans[l].nx; ++gx)
            if (LA[l].tf[gx])
                fclose(LA[l].tf[gx]);
        free(LA[l].tf), free(LA[l].recs), free(LA[l].rm), free(LA[l].ra), free(LA[l].rb), free(LA[l].rr);
    }
    free(LA);
    /* the snippets and the manifest */
    long lobes = 0, nonfinite = 0, magneg = 0;
    double worst_alb = 0.0;
    for (int l = 0; l < nl; ++l)
        lobes += stats[l].lobes, nonfinite += stats[l].nonfinite, magneg += stats[l].magnitude_neg,
            worst_alb = fmax(worst_alb, stats[l].worst_albedo_err);
    int gate_ok = nonfinite == 0 && magneg == 0 && g.pass && (!A->pair || g2.pass);
    /* a half table of two lobes (--lobes 2): its gate is energy and NaN (mf_prefilter_gate.half_table) */
    if (ok && o->lobe)
        fprintf(stderr,
                "mfkit prefilter: half %c of two lobes: gated on energy and NaN; the level and continuity checks are "
                "reported only (a half shades part of its footprint, and each level splits its own footprints)\n",
                "ab"[o->lobe - 1]);
    if (ok) {
        fprintf(stderr,
                "mfkit prefilter: gate %s: energy %.4g (bound %.3g) %s, non-finite %ld %s, negative magnitudes %ld, "
                "level %.4g (bound %.3g) %s; reported only: view spike %.4g (%.3g), texel spike %.4g (%.3g)\n",
                nonfinite == 0 && magneg == 0 && g.pass ? "passed" : "FAILED", g.worst_energy, g.max_energy, g.pass_energy ? "ok" : "FAIL",
                g.nan_entries + nonfinite, g.pass_nan && !nonfinite ? "ok" : "FAIL", magneg, g.worst_level, g.max_level,
                g.pass_level ? "ok" : o->lobe ? "above it, not gated for a half table" : "FAIL", g.worst_view_spike, g.max_view_spike, g.worst_texel_spike, g.max_texel_spike);
    }
    if (ok && !o->lobe) { /* the checks against the reference (a half table's: in its manifest, not gated) */
        if (g.cont_gated)
            fprintf(stderr,
                    "mfkit prefilter: continuity against the reference: texel spike %.4g, view spike %.4g, grazing views "
                    "%.4g (bound %.3g) %s; largest error %.4g of the albedo\n",
                    g.worst_cont_texel, g.worst_cont_view, g.worst_cont_grazing, g.max_cont_lambert,
                    g.pass_cont_texel && g.pass_cont_view && g.pass_cont_grazing ? "ok" : "FAIL", g.worst_ref_error);
        else
            fprintf(stderr,
                    "mfkit prefilter: reported only, error against the reference: texel spike %.4g, view spike %.4g, "
                    "grazing views %.4g, largest error %.4g of the albedo; extreme along every axis %.4g (bound %.3g%s)\n",
                    g.worst_cont_texel, g.worst_cont_view, g.worst_cont_grazing, g.worst_ref_error, g.worst_cont_cross,
                    g.max_cont_cross, g.pass_cont_cross ? "" : ", above it");
        fprintf(stderr,
                "mfkit prefilter: continuity across texels, the lobe's extreme beyond the reference's along every "
                "axis: %.4g (bound %.3g) %s\n",
                g.worst_cont_excess, g.max_cont_excess, g.pass_cont_excess ? "ok" : "FAIL");
        if (!g.pass_cont_excess)
            fprintf(stderr, "mfkit prefilter: worst continuity across texels at %s\n", g.where_cont_excess);
        fprintf(stderr,
                "mfkit prefilter: own fit, how much better a lobe shades a neighbour's reference than its own: "
                "texels %.4g, azimuths %.4g (bound %.3g) %s; reported: a neighbour's lobe better on the entry's "
                "reference %.4g\n",
                g.worst_cont_owner, g.worst_cont_owner_view, g.max_cont_owner, g.pass_cont_owner ? "ok" : "FAIL",
                g.worst_cont_dominated);
        if (!g.pass_cont_owner)
            fprintf(stderr, "mfkit prefilter: worst own fit at %s\n",
                    g.worst_cont_owner >= g.worst_cont_owner_view ? g.where_cont_owner : g.where_cont_owner_view);
        fprintf(stderr,
                "mfkit prefilter: own fit across elevations, how much better a lobe shades a theta neighbour's "
                "reference (at its lights) than its own: %.4g (bound %.3g%s) %s; reported: a theta neighbour's lobe "
                "better on the entry's reference %.4g\n",
                g.worst_cont_owner_theta, g.max_cont_owner_theta, g.owner_theta_gated ? "" : ", reported only",
                g.pass_cont_owner_theta ? "ok" : g.owner_theta_gated ? "FAIL" : "above it", g.worst_cont_dominated_theta);
        if (!g.pass_cont_owner_theta)
            fprintf(stderr, "mfkit prefilter: worst own fit across elevations at %s\n", g.where_cont_owner_theta);
        if (g.cont_gated && !(g.pass_cont_texel && g.pass_cont_view && g.pass_cont_grazing))
            fprintf(stderr, "mfkit prefilter: worst continuity at %s\n",
                    !g.pass_cont_texel ? g.where_cont_texel : !g.pass_cont_view ? g.where_cont_view : g.where_cont_grazing);
    }
    if (ok && !g.pass_energy)
        fprintf(stderr, "mfkit prefilter: worst energy at %s\n", g.where_energy);
    if (ok && A->pair) {
        const mf_prefilter_gate *p = &g2;
        fprintf(stderr,
                "mfkit prefilter: two-lobe gate (the sum of lobe_a's and lobe_b's lobes) %s: energy %.4g %s, NaN %ld %s, "
                "level %.4g %s, continuity across texels %.4g %s, own fit: texels %.4g, azimuths %.4g %s, elevations "
                "%.4g %s (the one-lobe table's bounds); reported: largest error %.4g of the albedo\n",
                p->pass ? "passed" : "FAILED", p->worst_energy, p->pass_energy ? "ok" : "FAIL", p->nan_entries,
                p->pass_nan ? "ok" : "FAIL", p->worst_level, p->pass_level ? "ok" : "FAIL", p->worst_cont_excess,
                p->pass_cont_excess ? "ok" : "FAIL", p->worst_cont_owner, p->worst_cont_owner_view,
                p->pass_cont_owner ? "ok" : "FAIL", p->worst_cont_owner_theta,
                p->pass_cont_owner_theta ? "ok" : p->owner_theta_gated ? "FAIL" : "above it", p->worst_ref_error);
        const char *w = p->pass ? NULL : !p->pass_energy ? p->where_energy : !p->pass_level ? p->where_level
                        : !p->pass_cont_excess ? p->where_cont_excess : !p->pass_cont_owner ? p->where_cont_owner
                        : !p->pass_cont_owner_theta ? p->where_cont_owner_theta : NULL;
        if (w)
            fprintf(stderr, "mfkit prefilter: two-lobe gate: worst at %s\n", w);
    }
    if (ok && !g.pass_level && !o->lobe)
        fprintf(stderr, "mfkit prefilter: worst level at %s\n", g.where_level);
    if (ok) {
        b.len = 0;
        write_glsl(&b, o);
        ok = begin_file(files, &nf, dir, "prefilter_lookup.glsl", msg, sizeof msg) && put_file(files[nf - 1].file, &b);
    }
    if (ok) {
        b.len = 0;
        write_hlsl(&b, o);
        ok = begin_file(files, &nf, dir, "prefilter_lookup.hlsl", msg, sizeof msg) && put_file(files[nf - 1].file, &b);
    }
    if (ok) {
        b.len = 0;
        char base[128];
        if (A->lambert)
            snprintf(base, sizeof base, "{\"model\": \"lambert\"}");
        else
            snprintf(base, sizeof base, "{\"model\": \"ggx\", \"alpha\": %.17g}", o->alpha);
        mf_buf_printf(&b,
                      "{\n  \"kind\": \"ltc_prefilter\",\n  \"map\": ");
        mf_json_string(&b, A->input);
        mf_buf_printf(&b, ",\n  \"width\": %d,\n  \"height\": %d,\n"
                      "  \"base_brdf\": %s,\n"
                      "  \"frame\": \"view-azimuth-aligned: normals rotated by -phi about z, view (sin theta, 0, cos "
                      "theta); M forward, divided by the norm of its last column\",\n"
                      "  \"below_horizon\": \"texel-frame view cosine clamped to %.17g at its azimuth (Nahmias 2022)\",\n"
                      "  \"axes\": {\"theta\": [",
                      A->W, A->H, base, MF_PREFILTER_COS_MIN);
        for (int a = 0; a < o->n_theta; ++a)
            mf_buf_printf(&b, "%s%.17g", a ? ", " : "", mf_prefilter_theta(o, a));
        mf_buf_printf(&b, "], \"phi\": [");
        for (int p = 0; p < o->n_phi; ++p)
            mf_buf_printf(&b, "%s%.17g", p ? ", " : "", mf_prefilter_phi(o, p));
        mf_buf_printf(&b,
                      "]},\n  \"fit\": {\"fitter\": \"mf_ltcfit_aniso general entry, 7-parameter lobe chart\", "
                      "\"fitter_revision\": %d, \"mfkit\": \"%s\", \"samples\": %d, \"max_iterations\": %d, \"seed\": %llu},\n"
                      "  \"level0\": \"not stored: %s\",\n"
                      "  \"magnitude\": %s,\n"
                      "  \"textures\": {\"layout\": \"per level k: prefilter_mip<k>_<t>.exr, t = 0, 1, 2, RGBA float32, an "
                      "atlas of n_theta x n_phi view tiles of w_k x h_k texels, view (i_theta, i_phi) at column i_phi * w_k, "
                      "row i_theta * h_k; upload as layer i_theta * n_phi + i_phi of a 2D array texture, MIP level k - 1\", "
                      "\"channels\": [[\"M00\", \"M01\", \"M02\", \"M10\"], [\"M11\", \"M12\", \"M20\", \"M21\"], "
                      "[\"M22\", \"magnitude\", \"0\", \"0\"]], \"lookup\": [\"prefilter_lookup.glsl\", "
                      "\"prefilter_lookup.hlsl\"]},\n"
                      "  \"tiling\": {\"tile\": %d, \"tiles\": %ld},\n"
                      "  \"levels\": [\n",
                      MF_PREFILTER_REVISION, MFKIT_VERSION, o->samples, o->max_iterations, (unsigned long long)o->seed,
                      A->lambert ? "Lambert per texel (1/pi about the texel's normal)" : "isotropic GGX LTC per texel",
                      o->keep_albedo
                          ? "\"albedo kept: the effective BRDF's albedo (albedo_mip<k>.npy) divided by the lobe's mass above "
                            "the horizon, (1 + n.z) / 2 with n = M^T z / |M^T z| (floored at 0.5), so that magnitude times the "
                            "clipped LTC integrates to the albedo; may exceed 1 where the lobe reaches below the horizon\""
                          : "\"the effective BRDF's albedo (as albedo_mip<k>.npy); the lobe's mass below the horizon is lost "
                            "(--no-keep-albedo)\"",
                      A->T, A->ntiles);
        for (int li = 0; li < nl; ++li) {
            const pf_plan *P = &A->plans[li];
            const pf_stats *S = &stats[li];
            mf_buf_printf(&b,
                          "    {\"level\": %d, \"width\": %d, \"height\": %d, \"matrices\": \"ltc_mip%d.npy\", "
                          "\"magnitude\": \"magnitude_mip%d.npy\", \"albedo\": \"albedo_mip%d.npy\", \"textures\": [\"prefilter_mip%d_0.exr\", "
                          "\"prefilter_mip%d_1.exr\", \"prefilter_mip%d_2.exr\"], \"lobes\": %ld, \"iterations\": %ld, "
                          "\"worst_residual\": %.6g, \"worst_albedo_err\": %.6g, \"not_converged\": %d, "
                          "\"magnitude_range\": [%.9g, %.9g]}%s\n",
                          P->level, P->w, P->h, P->level, P->level, P->level, P->level, P->level, P->level, S->lobes,
                          S->iterations,
                          S->worst_residual, S->worst_albedo_err, S->not_converged, S->mag_min, S->mag_max,
                          li + 1 < nl ? "," : "");
        }
        mf_buf_printf(&b, "  ],\n  \"lobes\": %ld,\n", lobes);
        if (o->lobe)
            mf_buf_printf(&b,
                          "  \"two_lobes\": {\"half\": \"%c\", \"other\": \"../lobe_%c\", \"one_lobe\": \"..\", \"split\": "
                          "\"each footprint's normals by 2-means (mf_prefilter_split_two), half a the larger mean n.x (then "
                          "n.y, n.z); albedo and magnitude are the half's share, so the two halves' shadings sum to the "
                          "footprint's; half b of a footprint with one distinct normal: identity, magnitude 0\", "
                          "\"gate\": \"energy and NaN gated; level and continuity reported only; the two "
                          "halves together: two_lobe_gate\"},\n",
                          "ab"[o->lobe - 1], "ba"[o->lobe - 1]);
        if (o->lobe && g_pf_pair_ran) {
            const mf_prefilter_gate *p = &g_pf_pair;
            mf_buf_printf(&b,
                          "  \"two_lobe_gate\": {\"passed\": %s, \"function\": \"mf_prefilter_gate_stream_set_lobes 2\", "
                          "\"measures\": \"the one-lobe table's checks and bounds on each entry's shading summed over "
                          "lobe_a and lobe_b\", \"energy\": %.6g, \"nan_entries\": %ld, \"level\": %.6g, "
                          "\"excess\": %.6g, \"own_fit\": %.6g, \"own_fit_azimuths\": %.6g, \"own_fit_elevations\": %.6g, "
                          "\"largest_error\": %.6g, \"where\": ",
                          p->pass ? "true" : "false", p->worst_energy, p->nan_entries, p->worst_level,
                          p->worst_cont_excess, p->worst_cont_owner, p->worst_cont_owner_view,
                          p->worst_cont_owner_theta, p->worst_ref_error);
            /* where: the first failing check's place (null when it passed) */
            if (p->pass)
                mf_buf_printf(&b, "null");
            else
                mf_json_string(&b, !p->pass_energy ? p->where_energy : !p->pass_nan ? "a non-finite shading"
                                   : !p->pass_level ? p->where_level : !p->pass_cont_excess ? p->where_cont_excess
                                   : !p->pass_cont_owner ? p->where_cont_owner : p->where_cont_owner_theta);
            mf_buf_printf(&b, "},\n");
        }
        mf_buf_printf(&b,
                      "  \"gate\": {\"passed\": %s, \"forced\": %s, \"function\": \"mf_prefilter_gate_run_ref\",%s\n"
                      "    \"energy\": {\"passed\": %s, \"worst\": %.6g, \"bound\": %.6g, \"where\": ",
                      gate_ok ? "true" : "false", !gate_ok && A->force ? "true" : "false",
                      o->lobe ? " \"half_table\": \"gated on energy and nan alone; every other check is reported only "
                                "(its passed flags are not part of passed)\","
                              : "",
                      g.pass_energy ? "true" : "false",
                      g.worst_energy, g.max_energy);
        mf_json_string(&b, g.where_energy);
        mf_buf_printf(&b, ", \"measures\": \"|magnitude (1 + n.z) / 2 / albedo - 1|, n = M^T z / |M^T z|\"},\n"
                          "    \"nan\": {\"passed\": %s, \"nonfinite_entries\": %ld, \"gate_nan_entries\": %ld, "
                          "\"negative_magnitudes\": %ld},\n"
                          "    \"level\": {\"passed\": %s, \"worst\": %.6g, \"bound\": %.6g, \"where\": ",
                      g.pass_nan && !nonfinite && !magneg ? "true" : "false", nonfinite, g.nan_entries, magneg,
                      g.pass_level ? "true" : "false", g.worst_level, g.max_level);
        mf_json_string(&b, g.where_level);
        mf_buf_printf(&b, ", \"measures\": \"|parent shading - mean of the 4 children's| / parent albedo, 6 quad lights\"},\n"
                          "    \"view_spike\": {\"reported_only\": true, \"within\": %s, \"worst\": %.6g, \"bound\": %.6g, "
                          "\"where\": ",
                      g.pass_view ? "true" : "false", g.worst_view_spike, g.max_view_spike);
        mf_json_string(&b, g.where_view);
        mf_buf_printf(&b, "},\n    \"texel_spike\": {\"reported_only\": true, \"within\": %s, \"worst\": %.6g, "
                          "\"bound\": %.6g, \"where\": ",
                      g.pass_texel ? "true" : "false", g.worst_texel_spike, g.max_texel_spike);
        mf_json_string(&b, g.where_texel);
        mf_buf_printf(&b, "},\n    \"continuity\": {\"reported_only\": %s, \"passed\": %s, \"bound\": %.6g, "
                          "\"function\": \"mf_prefilter_gate_run_ref\", "
                          "\"measures\": \"e = lobe shading - reference shading (each level-0 texel's base lobe, isotropic "
                          "LTC or exact cosine, averaged over the footprint), a lone extreme of e / albedo along texels "
                          "(periodic) and views\", \"texel\": {\"worst\": %.6g, \"where\": ",
                      g.cont_gated ? "false" : "true",
                      g.pass_cont_texel && g.pass_cont_view && g.pass_cont_grazing ? "true" : "false",
                      g.cont_gated ? g.max_cont_lambert : g.max_cont_texel, g.worst_cont_texel);
        mf_json_string(&b, g.where_cont_texel);
        mf_buf_printf(&b, "}, \"view\": {\"worst\": %.6g, \"where\": ", g.worst_cont_view);
        mf_json_string(&b, g.where_cont_view);
        mf_buf_printf(&b, "}, \"grazing\": {\"worst\": %.6g, \"where\": ", g.worst_cont_grazing);
        mf_json_string(&b, g.where_cont_grazing);
        mf_buf_printf(&b, "}, \"cross\": {\"reported_only\": true, \"within\": %s, \"worst\": %.6g, \"bound\": %.6g, "
                          "\"texel_axes\": %.6g, \"measures\": \"the smallest of the lone extremes of e / albedo along the "
                          "axes an entry has (texels x, y; theta; phi), entries with a texel axis\", \"where\": ",
                      g.pass_cont_cross ? "true" : "false", g.worst_cont_cross, g.max_cont_cross, g.worst_cont_cross_texel);
        mf_json_string(&b, g.where_cont_cross);
        mf_buf_printf(&b, "}, \"excess\": {\"passed\": %s, \"worst\": %.6g, \"bound\": %.6g, \"measures\": \"the "
                          "smallest, over the axes an entry has (texels x, y; theta; phi), of the lobe shading's lone "
                          "extreme less the reference's own, / albedo, entries with a texel axis\", \"where\": ",
                      g.pass_cont_excess ? "true" : "false", g.worst_cont_excess, g.max_cont_excess);
        mf_json_string(&b, g.where_cont_excess);
        mf_buf_printf(&b, "}, \"own_fit\": {\"passed\": %s, \"worst\": %.6g, \"bound\": %.6g, \"measures\": \"the "
                          "largest, over an entry's texel neighbours j (x, y, periodic; azimuths apart), of "
                          "|s - r| - |s - r_j|, s the lobe's shading and r the reference / albedo, |.| the largest "
                          "over the lights (a lobe copied, swapped or shifted from a neighbour)\", \"where\": ",
                      g.pass_cont_owner ? "true" : "false", g.worst_cont_owner, g.max_cont_owner);
        mf_json_string(&b, g.where_cont_owner);
        mf_buf_printf(&b, ", \"azimuths\": {\"worst\": %.6g, \"where\": ",
                      g.worst_cont_owner_view);
        mf_json_string(&b, g.where_cont_owner_view);
        mf_buf_printf(&b, "}, \"dominated\": {\"reported_only\": true, \"worst\": %.6g, \"measures\": \"the largest "
                          "|s - r| - |s_j - r| over texel and azimuth neighbours\", \"where\": ",
                      g.worst_cont_dominated);
        mf_json_string(&b, g.where_cont_dominated);
        mf_buf_printf(&b, "}, \"elevations\": {\"passed\": %s, \"reported_only\": %s, \"worst\": %.6g, \"bound\": %.6g, "
                          "\"measures\": \"the largest, over an entry's theta neighbours j (a +- 1), of |s - r| - "
                          "|x_j - r_j|, x_j the lobe's shading of j's lights and r_j j's reference of them / albedo\", "
                          "\"where\": ",
                      g.pass_cont_owner_theta ? "true" : "false", g.owner_theta_gated ? "false" : "true",
                      g.worst_cont_owner_theta, g.max_cont_owner_theta);
        mf_json_string(&b, g.where_cont_owner_theta);
        mf_buf_printf(&b, ", \"dominated\": {\"reported_only\": true, \"worst\": %.6g, \"measures\": \"the "
                          "largest |s - r| - |y_j - r|, y_j a theta neighbour's lobe under the entry's lights\", "
                          "\"where\": ",
                      g.worst_cont_dominated_theta);
        mf_json_string(&b, g.where_cont_dominated_theta);
        mf_buf_printf(&b, "}}}, \"largest_jump\": {\"texel\": %.6g, \"view\": %.6g}, \"largest_error\": %.6g},\n"
                          "    \"worst_albedo_quadrature_err\": %.6g,\n"
                          "    \"not_checked\": \"%s\"}\n}\n",
                      g.worst_jump_texel, g.worst_jump_view, g.worst_ref_error, worst_alb,
                      g.cont_gated ? "none"
                                   : "the specular table's error spikes against the reference are reported only (good "
                                     "runs show spikes as large as those of corrupted lobes); its continuity across "
                                     "texels is gated by continuity.excess (docs/prefilter.md, Gate)");
        ok = begin_file(files, &nf, dir, "prefilter.json", msg, sizeof msg) && put_file(files[nf - 1].file, &b);
    }
    int rc = 0;
    if (ok && !gate_ok && !A->force) {
        /* below the roughness the gate's bounds were set at, say so: there one lobe's own error reaches them
         * (docs/prefilter.md, "Fitter revision 9") */
        char low[320] = "";
        if (!A->lambert && o->alpha < MF_PREFILTER_GATE_TUNED_ALPHA)
            snprintf(low, sizeof low,
                     "; roughness %g is below the %g the gate is tuned at, where one lobe's own error reaches its "
                     "bounds: compare the lobes with the baselines (mfkit prefilter-eval) before using --force",
                     o->alpha, MF_PREFILTER_GATE_TUNED_ALPHA);
        rc = cli_error(k_cmd, "%s: the gate failed (see above); nothing written (--force writes it, marked unvalidated)%s",
                       A->input, low), rc = CLI_EXIT_CHECK_FAILED;
        mf_io_atomic_abort_all(files, (size_t)nf);
    } else if (!ok) {
        mf_io_atomic_abort_all(files, (size_t)nf);
        rc = cli_error(k_cmd, "%s", msg[0] ? msg : "write failed") * 0 + CLI_EXIT_IO;
    } else if (mf_io_atomic_commit_all(files, (size_t)nf, msg, sizeof msg) != MF_OK) {
        rc = cli_error(k_cmd, "%s", msg) * 0 + CLI_EXIT_IO;
    } else {
        struct timespec w1, c1;
        clock_gettime(CLOCK_MONOTONIC, &w1);
        clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &c1);
        double aw = (double)(w1.tv_sec - w0.tv_sec) + 1e-9 * (double)(w1.tv_nsec - w0.tv_nsec);
        double ac = (double)(c1.tv_sec - c0.tv_sec) + 1e-9 * (double)(c1.tv_nsec - c0.tv_nsec);
        fprintf(stderr,
                "mfkit prefilter: %ld lobes in %ld tiles (%ld resumed) on %d rank%s x %d thread%s (%ld lobes copied from "
                "identical footprints in the tiles this run fitted), %.3f s fitting wall (%.3f ms per lobe); assembly and gate %.3f s wall, %.3f s "
                "CPU (%.2f us per lobe)\n",
                lobes, A->ntiles, resumed, A->ranks, A->ranks > 1 ? "s" : "", o->threads, o->threads > 1 ? "s" : "", reused,
                secs,
                lobes ? 1e3 * secs / lobes : 0.0, aw, ac, lobes ? 1e6 * ac / lobes : 0.0);
    }
    mf_buf_free(&b);
    free(gl); /* shapes only: no arrays */
    free(files), free(stats);
    return rc;
}

static void pf_remove_work(const char *dir)
{
    char wd[4096], path[4400];
    snprintf(wd, sizeof wd, "%s/" PF_WORK, dir);
    DIR *d = opendir(wd);
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            snprintf(path, sizeof path, "%s/%s", wd, e->d_name);
            remove(path);
        }
    closedir(d);
    rmdir(wd);
}

static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; ++i)
        h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

/* ---- MPI ---------------------------------------------------------------------------------------- */

typedef struct { int rank, size, active; } pf_mpi;

static void pf_mpi_init(pf_mpi *m)
{
    m->rank = 0, m->size = 1, m->active = 0;
#ifdef MFKIT_CLI_HAVE_MPI
    /* only when started by a launcher (OpenMPI, PMIx or MPICH's hydra): a plain run stays serial */
    if (getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMIX_RANK") || getenv("PMI_SIZE")) {
        int inited = 0;
        MPI_Initialized(&inited);
        if (inited || MPI_Init(NULL, NULL) == MPI_SUCCESS) {
            MPI_Comm_rank(MPI_COMM_WORLD, &m->rank);
            MPI_Comm_size(MPI_COMM_WORLD, &m->size);
            m->active = 1;
        }
    }
#endif
}

/* The largest of every rank's v (v itself when serial). */
static int pf_mpi_max(const pf_mpi *m, int v)
{
#ifdef MFKIT_CLI_HAVE_MPI
    if (m->active) {
        int r = v;
        MPI_Allreduce(&v, &r, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
        return r;
    }
#endif
    (void)m;
    return v;
}

static long pf_mpi_sum(const pf_mpi *m, long v)
{
#ifdef MFKIT_CLI_HAVE_MPI
    if (m->active) {
        long r = v;
        MPI_Allreduce(&v, &r, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
        return r;
    }
#endif
    (void)m;
    return v;
}

static double pf_mpi_maxd(const pf_mpi *m, double v)
{
#ifdef MFKIT_CLI_HAVE_MPI
    if (m->active) {
        double r = v;
        MPI_Allreduce(&v, &r, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        return r;
    }
#endif
    (void)m;
    return v;
}

static int pf_mpi_bcast(const pf_mpi *m, int v)
{
#ifdef MFKIT_CLI_HAVE_MPI
    if (m->active)
        MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
    (void)m;
    return v;
}

static int pf_mpi_finish(const pf_mpi *m, int rc)
{
#ifdef MFKIT_CLI_HAVE_MPI
    if (m->active)
        MPI_Finalize();
#endif
    (void)m;
    return rc;
}

/* ---- the command ---------------------------------------------------------------------------------- */

/* stderr of the ranks > 0 while they read the arguments and the map (restored for the tiles) */
static int g_pf_saved_stderr = -1;
static void pf_unmute(void)
{
    if (g_pf_saved_stderr >= 0)
        fflush(stderr), dup2(g_pf_saved_stderr, 2), close(g_pf_saved_stderr), g_pf_saved_stderr = -1;
}

static int pf_views(const char *opt, const char *text, mf_prefilter_options *o)
{
    char tail;
    if (sscanf(text, "%dx%d%c", &o->n_theta, &o->n_phi, &tail) != 2 || o->n_theta < 2 || o->n_theta > 256 ||
        o->n_phi < 1 || o->n_phi > 256)
        return cli_error(k_cmd, "%s %s: expected TxP, 2..256 elevations x 1..256 azimuths", opt, text);
    return 0;
}

static int pf_table(const cli_val *v, const char *input, const char *dir, int lambert, mf_prefilter_options o, int T,
                    long max_tiles, int green_down, int encoding, int keep_work, int assemble, const char *pair,
                    const pf_mpi *mpi);

static int pf_main(int argc, char **argv, const pf_mpi *mpi)
{
    cli_val v[P_NOPTS];
    const char *pos[1];
    int npos = 0;
    int prc = cli_opt_parse(&k_prefilter_cmd, argc - 1, argv + 1, ~0u, k_cmd, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        if (mpi->rank == 0)
            cli_opt_usage(&k_prefilter_cmd, stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *input = pos[0], *dir = v[P_OUT].s;
    int base = v[P_BASE].set ? (int)v[P_BASE].i : 2; /* 0 ggx, 1 lambert, 2 both */
    if (base == 1 && v[P_ROUGHNESS].set)
        return cli_error(k_cmd, "--roughness: the Lambert base has no roughness (--base lambert)");
    int nlobes = v[P_LOBES].set ? (int)v[P_LOBES].i : 1;
    if (base == 1 && nlobes == 2)
        return cli_error(k_cmd, "--lobes 2: two lobes are fitted for the specular (GGX) table only, not with --base lambert");
    if (base != 2 && v[P_DIFFUSE_VIEWS].set)
        return cli_error(k_cmd, "--diffuse-views: only with --base both (--views sets the one table's views)");
    int T = v[P_TILE].set ? (int)v[P_TILE].i : 64;
    long max_tiles = v[P_MAX_TILES].set ? (long)v[P_MAX_TILES].i : -1;
    int green_down = v[P_GREEN].set && v[P_GREEN].i == 1;
    int encoding = v[P_ENCODING].set ? (int)v[P_ENCODING].i : 0;
    g_pf_quiet = v[P_QUIET].set;
    mf_prefilter_options o[2];
    char sub[4200];
    snprintf(sub, sizeof sub, "%s/diffuse", dir);
    for (int t = 0; t < 2; ++t) {
        int lambert = t == 1;
        if (lambert)
            mf_prefilter_options_default_diffuse(&o[t]);
        else
            mf_prefilter_options_default(&o[t]);
        o[t].keep_albedo = !v[P_NO_KEEP_ALBEDO].set;
        o[t].reuse = !v[P_NO_REUSE].set;
        if (!lambert && v[P_ROUGHNESS].set)
            o[t].alpha = v[P_ROUGHNESS].d;
        if (v[P_THREADS].set)
            o[t].threads = (int)v[P_THREADS].i;
        if (v[P_SAMPLES].set)
            o[t].samples = (int)v[P_SAMPLES].i;
        if (v[P_SEED].set)
            o[t].seed = v[P_SEED].u;
        int rc = 0;
        if (base == 2 && lambert && v[P_DIFFUSE_VIEWS].set)
            rc = pf_views("--diffuse-views", v[P_DIFFUSE_VIEWS].s, &o[t]);
        else if (v[P_VIEWS].set && (base != 2 || !lambert))
            rc = pf_views("--views", v[P_VIEWS].s, &o[t]);
        if (rc)
            return rc;
    }
    /* the steps in order: the specular table (DIR); with --lobes 2 its halves' fits (DIR/lobe_a, then
     * DIR/lobe_b), half b assembled through the two-lobe gate (the sum of both halves' lobes, half a's read
     * from its checkpoint), then half a assembled; then the diffuse table (DIR/diffuse).  A step that stops
     * (gate failure, --max-tiles, interruption, error) ends the run, and a rerun resumes.  Every checkpoint
     * stays until the last step is written: a rerun after a stop in a later step only reassembles the earlier
     * tables (the same bits) */
    char la[4200], lb[4200];
    snprintf(la, sizeof la, "%s/lobe_a", dir);
    snprintf(lb, sizeof lb, "%s/lobe_b", dir);
    typedef struct { const char *dir; int lambert, lobe, assemble; const char *pair; } pf_step;
    pf_step step[6];
    int ns = 0;
    if (base != 1)
        step[ns++] = (pf_step){dir, 0, 0, 1, NULL};
    if (nlobes == 2) {
        step[ns++] = (pf_step){la, 0, 1, 0, NULL};
        step[ns++] = (pf_step){lb, 0, 2, 1, la};
        step[ns++] = (pf_step){la, 0, 1, 1, NULL};
    }
    if (base != 0)
        step[ns++] = (pf_step){base == 1 ? dir : sub, 1, 0, 1, NULL};
    int rc = 0;
    for (int t = 0; t < ns && !rc; ++t) {
        mf_prefilter_options ot = o[step[t].lambert];
        ot.lobe = step[t].lobe;
        rc = pf_table(v, input, step[t].dir, step[t].lambert, ot, T, max_tiles, green_down, encoding, t + 1 < ns,
                      step[t].assemble, step[t].pair, mpi);
    }
    for (int t = 0; t + 1 < ns && !rc && mpi->rank == 0; ++t)
        pf_remove_work(step[t].dir);
    return rc;
}

/* One table: fits its tiles (those not in its checkpoint), then, with assemble, streams them into its files
 * through the gate (rank 0); without, it stops there and keeps the checkpoint.  pair: --lobes 2, half b: half
 * a's directory, whose checkpoint (fitted, not yet assembled) feeds the two-lobe gate. */
static int pf_table(const cli_val *v, const char *input, const char *dir, int lambert, mf_prefilter_options o, int T,
                    long max_tiles, int green_down, int encoding, int keep_work, int assemble, const char *pair,
                    const pf_mpi *mpi)
{
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
    pf_tile *tiles = NULL;
    pf_base ab = {0, 0, 0, 0, 0, NULL};
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
    const int W = img.width, H = img.height, nl = ilog2_levels(W, H);
    pf_plan plans[16];
    long ntiles = pf_make_tiles(W, H, T, plans, &tiles);
    if (ntiles < 0) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
        goto done;
    }
    /* the work directory and its run record (rank 0 checks it, the others wait); gate_part: the size of a
     * region tile's part of the gate in its file, so a gate with another set of checks refuses the
     * checkpoint instead of misreading it */
    char wd[4096], runp[4400];
    snprintf(wd, sizeof wd, "%s/" PF_WORK, dir);
    snprintf(runp, sizeof runp, "%s/run.txt", wd);
    if (mpi->rank == 0) {
        mf_buf key = {0};
        uint64_t h = fnv1a(1469598103934665603ull, normals, sizeof(double) * 3 * (size_t)W * H);
        mf_buf_printf(&key,
                      "mfkit prefilter work 5\ngate_part %zu\nrevision %d\nmap %d x %d fnv1a64 %016llx\nbase %s\n"
                      "keep_albedo %d\nalpha %.17g\nviews %d x %d\nsamples %d\nmax_iterations %d\nseed %llu\ntile %d\n",
                      sizeof(mf_prefilter_gate_part), MF_PREFILTER_REVISION, W, H, (unsigned long long)h, lambert ? "lambert" : "ggx", o.keep_albedo, o.alpha, o.n_theta, o.n_phi, o.samples,
                      o.max_iterations, (unsigned long long)o.seed, T);
        if (o.lobe)
            mf_buf_printf(&key, "lobe %d\n", o.lobe);
        unsigned char *old = NULL;
        size_t oldlen = 0;
        int missing = 0;
        if (mf_io_make_dirs(wd, msg, sizeof msg) != MF_OK) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: %s", dir, msg);
        } else if (mf_io_read_file(runp, runp, &old, &oldlen, &missing, msg, sizeof msg) == MF_OK) {
            if (oldlen != key.len || memcmp(old, key.data, key.len))
                rc = cli_error(k_cmd, "%s: the checkpoint of a run with another map, options, fitter revision "
                                      "or checkpoint format; remove it to start over", wd);
        } else if (!missing) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
        } else if (mf_io_write_buf_atomic(runp, &key, msg, sizeof msg) != MF_OK) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "%s", msg);
        }
        free(old);
        mf_buf_free(&key);
    }
    rc = pf_mpi_bcast(mpi, rc);
    if (rc)
        goto done;
    pf_unmute(); /* a tile's error is its rank's own */
    struct sigaction sa, old_int, old_term;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = pf_on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);

    /* the albedo base of the footprint tiles: this rank's blocks not in the checkpoint (all of them,
     * whatever --max-tiles: one pass of one-texel albedos over the map), then a barrier, then every
     * rank reads all blocks */
    ab.rw = W < T ? W : T, ab.rh = H < T ? H : T;
    ab.lr = ilog2_levels(ab.rw, ab.rh), ab.nbx = W / ab.rw, ab.nby = H / ab.rh;
    int stopped_a = 0;
    if (nl > ab.lr) {
        long nb = (long)ab.nbx * ab.nby;
        pf_queue qa;
        memset(&qa, 0, sizeof qa);
        qa.todo = malloc(sizeof(long) * (size_t)(nb / mpi->size + 1));
        if (!qa.todo)
            rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
        for (long b = mpi->rank; b < nb && qa.todo; b += mpi->size) {
            char path[4400];
            block_path(path, sizeof path, dir, b);
            if (access(path, F_OK) != 0)
                qa.todo[qa.ntodo++] = b;
        }
        qa.normals = normals, qa.W = W, qa.ab = &ab, qa.blocks = 1, qa.dir = dir, qa.input = input;
        qa.max_tiles = -1;
        int wa = qa.ntodo < o.threads ? (int)(qa.ntodo > 0 ? qa.ntodo : 1) : o.threads;
        qa.o = o;
        qa.o.threads = o.threads / wa > 0 ? o.threads / wa : 1;
        if (!rc)
            pf_run_queue(&qa, wa);
        free(qa.todo);
        if (!rc)
            rc = qa.rc;
        stopped_a = qa.stopped;
    }
    rc = pf_mpi_max(mpi, rc); /* the barrier: every rank's blocks are written */
    stopped_a = pf_mpi_max(mpi, stopped_a);
    if (!rc && !stopped_a && nl > ab.lr)
        rc = pf_read_base(dir, (size_t)o.n_theta * o.n_phi, &ab);

    /* this rank's tiles not in the checkpoint, largest footprints (the last tiles) first: the
     * longest jobs start first, and a first --max-tiles slice meets the memory peak */
    long resumed = 0;
    pf_queue q;
    memset(&q, 0, sizeof q);
    q.todo = malloc(sizeof(long) * (size_t)(ntiles / mpi->size + 1));
    if (!q.todo)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
    for (long i = mpi->rank; i < ntiles && q.todo; i += mpi->size) {
        char path[4400];
        tile_path(path, sizeof path, dir, ntiles - 1 - i);
        if (access(path, F_OK) == 0)
            ++resumed;
        else
            q.todo[q.ntodo++] = ntiles - 1 - i;
    }
    q.normals = normals, q.W = W, q.H = H, q.tiles = tiles, q.ab = &ab, q.dir = dir, q.input = input;
    q.max_tiles = max_tiles;
    /* several tiles at once when there are enough (a footprint tile is one fit job: threads inside it
     * would idle), else the threads inside the tiles; the bits depend on neither. The tiles counted
     * are the ones this run fits: a --max-tiles slice's own, not all those left in the checkpoint */
    long nrun = q.max_tiles >= 0 && q.max_tiles < q.ntodo ? q.max_tiles : q.ntodo;
    int workers = nrun < o.threads ? (int)(nrun > 0 ? nrun : 1) : o.threads;
    q.o = o;
    q.o.threads = o.threads / workers > 0 ? o.threads / workers : 1;
    pf_progress prog = {.show = !g_pf_quiet && mpi->rank == 0 && isatty(fileno(stderr)),
                        .what = lambert ? "diffuse" : o.lobe == 1 ? "specular, half a" : o.lobe == 2 ? "specular, half b" : "specular"};
    atomic_init(&prog.done, 0);
    atomic_init(&prog.last_ms, -1000);
    clock_gettime(CLOCK_MONOTONIC, &prog.t0);
    for (long i = 0; i < nrun; ++i)
        prog.total += pf_tile_lobes(&tiles[q.todo[i]], (long)o.n_theta * o.n_phi);
    if (prog.show)
        q.o.progress = pf_progress_cb, q.o.progress_user = &prog;
    if (stopped_a)
        q.stopped = stopped_a;
    else if (!rc)
        pf_run_queue(&q, workers);
    if (prog.show && atomic_load(&prog.done) > 0)
        fprintf(stderr, "\rmfkit prefilter: %s: %ld lobes fitted in %.0f s%*s\n", prog.what, atomic_load(&prog.done),
                1e-3 * (double)pf_ms_since(&prog.t0), 20, "");
    clock_gettime(CLOCK_MONOTONIC, &t1);
    sigaction(SIGINT, &old_int, NULL);
    sigaction(SIGTERM, &old_term, NULL);
    free(q.todo);
    if (!rc)
        rc = q.rc;
    int stopped = q.stopped;
    double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    rc = pf_mpi_max(mpi, rc);
    stopped = pf_mpi_max(mpi, stopped);
    resumed = pf_mpi_sum(mpi, resumed);
    long reused = pf_mpi_sum(mpi, q.reused);
    secs = pf_mpi_maxd(mpi, secs);
    if (!rc && stopped) {
        long done_tiles = 0;
        for (long k = 0; k < ntiles && mpi->rank == 0; ++k) {
            char path[4400];
            tile_path(path, sizeof path, dir, k);
            done_tiles += access(path, F_OK) == 0;
        }
        if (mpi->rank == 0)
            fprintf(stderr, "mfkit prefilter: %s after %ld of %ld tiles; rerun the same command to resume from %s\n",
                    stopped == CLI_EXIT_INTERRUPTED ? "interrupted" : "stopped (--max-tiles)", done_tiles, ntiles, wd);
        rc = stopped;
        goto done;
    }
    if (!rc && !assemble && mpi->rank == 0)
        fprintf(stderr, "mfkit prefilter: %s: %ld tiles fitted (%ld resumed) (%ld lobes copied from identical footprints) "
                        "in %.3f s wall; it is assembled after half b, whose assembly runs the two-lobe gate\n",
                dir, ntiles, resumed, reused, secs);
    if (rc || !assemble)
        goto done;
    if (mpi->rank == 0) {
        pf_assembly A = {dir, input, W, H, nl, T, &o, plans, ntiles, mpi->size, lambert, v[P_FORCE].set, normals, pair};
        if (prog.show)
            fprintf(stderr, "mfkit prefilter: %s: assembling the levels and running the gate\n", prog.what);
        rc = pf_assemble(&A, secs, resumed, reused);
        if (!rc && !keep_work)
            pf_remove_work(dir);
    }
    rc = pf_mpi_bcast(mpi, rc);
done:
    free(ab.alb);
    free(normals);
    free(tiles);
    mf_image_free(&img);
    mf_image_info_free(&info);
    return rc;
}

int cli_prefilter(int argc, char **argv)
{
    pf_mpi mpi;
    pf_mpi_init(&mpi);
    /* every rank sees the same arguments and map, hence the same usage and input errors: rank 0 alone reports them */
    if (mpi.rank != 0) {
        fflush(stderr);
        g_pf_saved_stderr = dup(2);
        FILE *null = fopen("/dev/null", "w");
        if (null)
            dup2(fileno(null), 2), fclose(null);
    }
    int rc = pf_main(argc, argv, &mpi);
    pf_unmute();
    return pf_mpi_finish(&mpi, rc);
}

#endif
