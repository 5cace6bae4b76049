/*
 * cli_maps.c -- `mfkit maps lean|leadr|bump-roughness|toksvig INPUT --out PREFIX`: slope-moment
 * maps and their box-filtered MIP chains from a normal or height map (docs/cli.md, mf_maps.h).
 * Exit code 0 on success, 2 for a usage or input error (bad option, wrong channel count, invalid
 * texel), 3 for an I/O error (unreadable input, output directory missing).  Every output file is
 * first written to a temporary beside it; they are renamed only when all were written and synced
 * (mf_io_atomic_commit_all), so a failure leaves no output.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include <stdlib.h>
#include <string.h>

static const char *const k_cmd = "maps";

static const char *const k_green_names[] = {"up", "down", NULL};
static const char *const k_encoding_names[] = {"auto", "unorm", "raw", NULL};
static const char *const k_edge_names[] = {"wrap", "clamp", NULL};
enum { M_OUT, M_GREEN, M_ENCODING, M_TOLERANCE, M_HEIGHT, M_HEIGHT_SCALE, M_TEXEL_SIZE, M_EDGE, M_BASE_ALPHA,
       M_TABLE_FORMAT, M_QUIET, M_NOPTS };
static const cli_opt k_maps_opts[M_NOPTS] = {
    {.name = "--out", .metavar = "PREFIX", .kind = CLI_OPT_STRING, .required = 1,
     .help = "output file prefix (its directory must exist)"},
    {.name = "--green", .kind = CLI_OPT_ENUM, .choices = k_green_names, .def = "up",
     .help = "normal maps: green is +y up (OpenGL) or down (DirectX)"},
    {.name = "--encoding", .kind = CLI_OPT_ENUM, .choices = k_encoding_names, .def = "auto",
     .help = "normal maps: unorm n = 2c - 1, raw n = c; auto: unorm for unsigned integer files (PNG, TIFF), raw "
             "for float (EXR, float TIFF)"},
    {.name = "--normal-tolerance", .metavar = "E", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = INFINITY,
     .def = "1e-3 + sqrt(3)/(2^bits - 1) for integer files, 1e-3 for float files", .help = "accepted | |n| - 1 |"},
    {.name = "--height", .kind = CLI_OPT_FLAG, .help = "the input is a height map (first channel)"},
    {.name = "--height-scale", .metavar = "S", .kind = CLI_OPT_DOUBLE, .dlo = -INFINITY, .dhi = INFINITY, .def = "1",
     .help = "height units per stored value"},
    {.name = "--texel-size", .metavar = "T", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = INFINITY, .lo_open = 1,
     .def = "1", .help = "distance between texels, same unit"},
    {.name = "--edge", .kind = CLI_OPT_ENUM, .choices = k_edge_names, .def = "wrap",
     .help = "height maps: periodic central differences, or one-sided differences at the borders"},
    {.name = "--base-alpha", .metavar = "A", .kind = CLI_OPT_DOUBLE, .dlo = 0.0, .dhi = INFINITY, .def = "0",
     .help = "base Beckmann roughness, added as covariance A^2/2"},
    {.name = "--table-format", .metavar = "LIST", .kind = CLI_OPT_STRING,
     .help = "also write every level's moments as a moment_map table in each format of LIST (comma-separated "
             "extensions: exr,dds,json,npy,h,glsl,hlsl,csv): PREFIX_moments_mip<k>.<ext> (lean, leadr, "
             "bump-roughness)"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no progress on stderr (shown only on a terminal anyway)"},
};
static const cli_command k_maps_cmd = {
    .name = "maps",
    .synopsis = "lean|leadr|bump-roughness|toksvig INPUT",
    .min_pos = 0, /* checked with their own messages */
    .max_pos = 2,
    .description =
        "Reads a tangent-space normal map (or, with --height, a height map) and writes the moment or\n"
        "roughness maps of every level of a box-filtered MIP chain (computed in double) as float EXR:\n"
        "  leadr           PREFIX_m1_mip<k>.exr  R,G,B = E[x], E[y], 0   (mfkit/LEADR slopes -n.xy/n.z)\n"
        "                  PREFIX_m2_mip<k>.exr  R,G,B = E[x^2], E[y^2], E[xy]\n"
        "  lean            the same files with R,G = E[n.x/n.z], E[n.y/n.z] = -E[x], -E[y] (LEAN's sign)\n"
        "  bump-roughness  PREFIX_roughness_mip<k>.exr  alpha_1, alpha_2, dir_x, dir_y (Beckmann, Hery)\n"
        "  toksvig         PREFIX_toksvig_mip<k>.exr    alpha, len, n_x, n_y, n_z (Toksvig)\n"
        "  --table-format  PREFIX_moments_mip<k>.<ext>  the level's moments E[x], E[y], E[x^2], E[xy], E[y^2]\n"
        "                  as a moment_map table (docs/tables.md), in every table format\n"
        "Level k + 1 halves each side of level k (odd sizes round down, exact area-weighted box).\n"
        "Frame: x to the right, y up the image (OpenGL); base roughness added as covariance.\n",
    .opts = k_maps_opts,
    .nopts = M_NOPTS,
    .epilog = "exit status: 0 success, 2 usage or input error, 3 I/O error\n",
};

#ifndef MFKIT_CLI_HAVE_IMAGE

int cli_maps(int argc, char **argv)
{
    return cli_opt_unavailable(&k_maps_cmd, k_cmd, "OpenImageIO", "MFKIT_WITH_OIIO", argc, argv);
}

#else

#include "mfkit/io/mf_image.h"
#include "mfkit/io/mf_table_io.h"
#include "mfkit/mfkit.h"

#include <errno.h>
#include <sys/stat.h>
#include <unistd.h>

static void usage(FILE *f) { cli_opt_usage(&k_maps_cmd, f); }

typedef enum { MODE_LEAN, MODE_LEADR, MODE_BUMP, MODE_TOKSVIG } maps_mode;

typedef struct {
    maps_mode mode;
    const char *mode_name, *input, *prefix;
    int green_down, height, quiet;
    int encoding; /* 0 auto, 1 unorm, 2 raw */
    double tolerance; /* < 0: default */
    double height_scale, texel_size, base_alpha;
    mf_map_edge edge;
    const char *table_formats; /* --table-format LIST, or NULL */
    int ntables;
    char table_ext[8][8];      /* the extensions of LIST */
    char *table_dir;           /* the temporary directory of the table files (malloc), or NULL */
} maps_args;

/* The output files: each written to its temporary (mf_io_atomic), all renamed together at the
 * end (mf_io_atomic_commit_all). */
typedef struct {
    mf_io_atomic *f;
    int n, cap;
} out_list;

/* PREFIX_TAG_mip<level>.exr */
static char *level_path(const char *prefix, const char *tag, int level)
{
    size_t n = strlen(prefix) + strlen(tag) + 64;
    char *s = malloc(n);
    if (s)
        snprintf(s, n, "%s_%s_mip%d.exr", prefix, tag, level);
    return s;
}

/* Writes one level file to its temporary; returns the exit code (0 ok). */
static int write_level(out_list *l, const maps_args *a, const char *tag, int level, const mf_image *img,
                       const char *const *names, const char *content)
{
    if (l->n == l->cap) {
        int nc = l->cap ? 2 * l->cap : 16;
        mf_io_atomic *p = realloc(l->f, sizeof *p * (size_t)nc);
        if (!p)
            return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
        l->f = p;
        l->cap = nc;
    }
    char msg[1024];
    char *path = level_path(a->prefix, tag, level);
    if (!path)
        return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
    mf_io_atomic *o = &l->f[l->n];
    mf_status st = mf_io_atomic_begin(o, path, msg, sizeof msg);
    free(path);
    if (st != MF_OK) {
        cli_error(k_cmd, "%s", msg);
        return cli_exit_code(st);
    }
    ++l->n;
    char level_s[32], alpha_s[64];
    snprintf(level_s, sizeof level_s, "%d", level);
    snprintf(alpha_s, sizeof alpha_s, "%.17g", a->base_alpha);
    const char *an[] = {"mfkit:maps_mode", "mfkit:maps_content", "mfkit:mip_level", "mfkit:base_alpha",
                        "mfkit:frame", "mfkit:source"};
    const char *av[] = {a->mode_name, content, level_s, alpha_s,
                        "tangent frame x = +column, y = up the image (OpenGL); slopes (-n.x/n.z, -n.y/n.z)",
                        a->input};
    mf_image_write_options opt;
    memset(&opt, 0, sizeof opt);
    opt.channel_names = names;
    opt.nattribs = (int)(sizeof an / sizeof an[0]);
    opt.attrib_names = an;
    opt.attrib_values = av;
    st = mf_image_write_into(o, img, &opt, msg, sizeof msg);
    if (st != MF_OK) {
        cli_error(k_cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return cli_exit_code(st);
    }
    return 0;
}

/* The moment_map tables of level `level` (mf_map_moments_to_table) in every --table-format, written
 * (each atomically, with its sidecar) into the temporary directory a->table_dir under their final
 * names, so that generated code names the final file; mf_io_atomic_commit_all moves them beside the EXRs. */
static int write_level_tables(out_list *l, const maps_args *a, const mf_map *m, int level)
{
    mf_table t;
    mf_status st = mf_map_moments_to_table(m, level, &t);
    if (st != MF_OK)
        return cli_error(k_cmd, "level %d: cannot make its table: %s", level, mf_status_str(st)), CLI_EXIT_IO;
    if (mf_table_set_meta(&t, "source", a->input) != MF_OK || mf_table_set_meta(&t, "tool", "mfkit maps") != MF_OK) {
        mf_table_free(&t);
        return cli_error(k_cmd, "level %d: table metadata full", level), CLI_EXIT_IO;
    }
    const char *slash = strrchr(a->prefix, '/');
    const char *base = slash ? slash + 1 : a->prefix;
    size_t dirlen = slash ? (size_t)(slash - a->prefix) + 1 : 0;
    int rc = 0;
    for (int j = 0; j < a->ntables && rc == 0; ++j) {
        size_t n = strlen(a->table_dir) + strlen(a->prefix) + 64;
        char *tmp = malloc(n), *fin = malloc(n), *side_tmp = malloc(n + 8), *side_fin = malloc(n + 8);
        if (!tmp || !fin || !side_tmp || !side_fin) {
            free(tmp), free(fin), free(side_tmp), free(side_fin);
            rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
            break;
        }
        snprintf(tmp, n, "%s/%s_moments_mip%d.%s", a->table_dir, base, level, a->table_ext[j]);
        snprintf(fin, n, "%.*s%s_moments_mip%d.%s", (int)dirlen, a->prefix, base, level, a->table_ext[j]);
        snprintf(side_tmp, n + 8, "%s.json", tmp);
        snprintf(side_fin, n + 8, "%s.json", fin);
        char msg[1024];
        st = mf_table_write(tmp, &t, NULL, NULL, msg, sizeof msg);
        if (st != MF_OK) {
            rc = cli_exit_code(st), cli_error(k_cmd, "%s: %s", fin, msg);
        } else {
            struct stat sb;
            int has_side = stat(side_tmp, &sb) == 0;
            /* already complete under their final names: the list's commit_all fsyncs them by name
             * (file NULL) and renames them with the EXRs, all or nothing */
            for (int k = 0; k < 1 + has_side && rc == 0; ++k) {
                if (l->n == l->cap) {
                    int nc = l->cap ? 2 * l->cap : 16;
                    mf_io_atomic *q = realloc(l->f, sizeof *q * (size_t)nc);
                    if (!q) {
                        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
                        break;
                    }
                    l->f = q;
                    l->cap = nc;
                }
                mf_io_atomic *o = &l->f[l->n++];
                memset(o, 0, sizeof *o);
                o->tmp_path = k ? side_tmp : tmp;
                o->path = k ? side_fin : fin;
                if (k)
                    side_tmp = side_fin = NULL;
                else
                    tmp = fin = NULL;
            }
        }
        free(tmp), free(fin), free(side_tmp), free(side_fin);
    }
    mf_table_free(&t);
    return rc;
}

/* The directory part of the prefix must exist. */
static int check_prefix_dir(const char *prefix)
{
    const char *slash = strrchr(prefix, '/');
    if (!slash)
        return 0;
    size_t n = (size_t)(slash - prefix);
    char *dir = malloc(n + 2);
    if (!dir)
        return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
    if (n == 0)
        strcpy(dir, "/");
    else {
        memcpy(dir, prefix, n);
        dir[n] = '\0';
    }
    struct stat sb;
    int rc = 0;
    if (stat(dir, &sb) != 0)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: directory '%s': %s", prefix, dir, strerror(errno));
    else if (!S_ISDIR(sb.st_mode))
        rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: '%s' is not a directory", prefix, dir);
    free(dir);
    return rc;
}

/* Bits of an unsigned integer pixel type ("uint8" -> 8), 0 for other types; *is_signed_int set
 * for "int8", "int16", ... */
static int uint_bits(const char *type, int *is_signed_int)
{
    *is_signed_int = 0;
    if (!strncmp(type, "uint", 4)) {
        int b = atoi(type + 4);
        return b > 0 ? b : 8;
    }
    if (!strncmp(type, "int", 3))
        *is_signed_int = 1;
    return 0;
}

/* Decodes, checks and normalises the normals of img into a 3-channel map (y-up frame). */
static int decode_normals(const maps_args *a, const mf_image *img, const char *pixel_type, mf_map *out)
{
    int signed_int;
    int bits = uint_bits(pixel_type, &signed_int);
    int unorm = a->encoding == 1 || (a->encoding == 0 && bits > 0);
    double tol = a->tolerance;
    if (tol < 0)
        tol = 1e-3 + (bits > 0 && bits < 32 ? sqrt(3.0) / (ldexp(1.0, bits) - 1.0) : 0.0);
    if (mf_map_alloc(out, img->width, img->height, 3) != MF_OK)
        return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
    const char *chname[3] = {"R", "G", "B"};
    for (int j = 0; j < img->height; ++j)
        for (int i = 0; i < img->width; ++i) {
            size_t t = (size_t)j * img->width + i;
            const float *p = img->pixels + t * (size_t)img->channels;
            double n[3];
            for (int c = 0; c < 3; ++c) {
                if (!isfinite(p[c])) {
                    mf_map_free(out);
                    return cli_error(k_cmd, "%s: texel (%d, %d) (column, row from the top): channel %s is %s",
                                     a->input, i, j, chname[c], isnan(p[c]) ? "NaN" : "infinite");
                }
                n[c] = unorm ? 2.0 * (double)p[c] - 1.0 : (double)p[c];
            }
            if (a->green_down)
                n[1] = -n[1];
            double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(fabs(len - 1.0) <= tol)) {
                mf_map_free(out);
                return cli_error(k_cmd,
                                 "%s: texel (%d, %d) (column, row from the top): normal (%.6g, %.6g, %.6g) has length "
                                 "%.6g, not 1 within %.3g (see --encoding, --normal-tolerance)",
                                 a->input, i, j, n[0], n[1], n[2], len, tol);
            }
            if (!(n[2] > 0.0)) {
                mf_map_free(out);
                return cli_error(k_cmd,
                                 "%s: texel (%d, %d) (column, row from the top): n.z = %.6g <= 0 (a tangent-space "
                                 "normal must point out of the surface; see --encoding)",
                                 a->input, i, j, n[2]);
            }
            for (int c = 0; c < 3; ++c)
                out->data[3 * t + c] = n[c] / len;
        }
    return 0;
}

/* Unit normals (-sx, -sy, 1)/|.| of a slope map. */
static int normals_from_slopes(const mf_map *s, mf_map *out)
{
    if (mf_map_alloc(out, s->width, s->height, 3) != MF_OK)
        return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
    size_t n = (size_t)s->width * s->height;
    for (size_t t = 0; t < n; ++t) {
        double sx = s->data[2 * t], sy = s->data[2 * t + 1];
        double inv = 1.0 / sqrt(1.0 + sx * sx + sy * sy);
        out->data[3 * t + 0] = -sx * inv;
        out->data[3 * t + 1] = -sy * inv;
        out->data[3 * t + 2] = inv;
    }
    return 0;
}

/* Writes the output files of one level of the chain `level_map` (moments or normals). */
static int emit_level(out_list *l, const maps_args *a, const mf_map *m, int level)
{
    const int w = m->width, h = m->height;
    const size_t n = (size_t)w * h;
    mf_image img = {w, h, 3, NULL};
    const double b = 0.5 * a->base_alpha * a->base_alpha; /* Beckmann: sigma^2 = alpha^2 / 2 */
    int rc = 0;
    if (a->mode == MODE_LEAN || a->mode == MODE_LEADR) {
        img.pixels = malloc(sizeof(float) * 3 * n);
        if (!img.pixels)
            return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
        const double sign = a->mode == MODE_LEAN ? -1.0 : 1.0;
        for (size_t t = 0; t < n; ++t) {
            const double *p = m->data + t * MF_MAP_MOMENTS;
            img.pixels[3 * t + 0] = (float)(sign * p[MF_MAP_MEAN_X]);
            img.pixels[3 * t + 1] = (float)(sign * p[MF_MAP_MEAN_Y]);
            img.pixels[3 * t + 2] = 0.0f;
        }
        static const char *const rgb[] = {"R", "G", "B"};
        rc = write_level(l, a, "m1", level, &img, rgb,
                         a->mode == MODE_LEAN ? "R = E[n.x/n.z], G = E[n.y/n.z] (LEAN sign: -E[slope]), B = 0"
                                              : "R = E[x], G = E[y] (slopes -n.x/n.z, -n.y/n.z), B = 0");
        if (rc == 0) {
            for (size_t t = 0; t < n; ++t) {
                const double *p = m->data + t * MF_MAP_MOMENTS;
                img.pixels[3 * t + 0] = (float)(p[MF_MAP_M_XX] + b);
                img.pixels[3 * t + 1] = (float)(p[MF_MAP_M_YY] + b);
                img.pixels[3 * t + 2] = (float)p[MF_MAP_M_XY];
            }
            rc = write_level(l, a, "m2", level, &img, rgb,
                             "R = E[x^2] + base, G = E[y^2] + base, B = E[xy] (base = base_alpha^2 / 2)");
        }
    } else if (a->mode == MODE_BUMP) {
        img.channels = 4;
        img.pixels = malloc(sizeof(float) * 4 * n);
        if (!img.pixels)
            return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
        for (size_t t = 0; t < n; ++t) {
            mf_slope_moments mo = mf_map_moments_at(m, (int)(t % (size_t)w), (int)(t / (size_t)w));
            mf_gaussian_slopes g = mf_moments_to_gaussian(&mo);
            mf_sym2 cov = {g.var_x, g.cov_xy, g.var_y};
            mf_aniso_roughness r = mf_hery_bump_roughness(a->base_alpha, a->base_alpha, cov);
            double dx = r.dir1[0], dy = r.dir1[1];
            if (dx < 0.0 || (dx == 0.0 && dy < 0.0))
                dx = -dx, dy = -dy; /* an axis: the sign with dir_x >= 0 */
            img.pixels[4 * t + 0] = (float)r.alpha1;
            img.pixels[4 * t + 1] = (float)r.alpha2;
            img.pixels[4 * t + 2] = (float)dx;
            img.pixels[4 * t + 3] = (float)dy;
        }
        static const char *const names[] = {"alpha_1", "alpha_2", "dir_x", "dir_y"};
        rc = write_level(l, a, "roughness", level, &img, names,
                         "Beckmann alpha_1 >= alpha_2 along the unit axes (dir_x, dir_y) and (-dir_y, dir_x), "
                         "dir_x >= 0 (Hery 2014 Eq. 11-12, mf_hery_bump_roughness)");
    } else {
        img.channels = 5;
        img.pixels = malloc(sizeof(float) * 5 * n);
        if (!img.pixels)
            return cli_error(k_cmd, "out of memory"), CLI_EXIT_IO;
        for (size_t t = 0; t < n; ++t) {
            const double *p = m->data + 3 * t;
            double len = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            if (len > 1.0 && len <= 1.0 + 1e-12)
                len = 1.0; /* rounding of an average of unit vectors */
            double alpha = mf_toksvig_beckmann_alpha(len, a->base_alpha);
            img.pixels[5 * t + 0] = (float)alpha;
            img.pixels[5 * t + 1] = (float)len;
            for (int c = 0; c < 3; ++c)
                img.pixels[5 * t + 2 + c] = (float)(len > 0.0 ? p[c] / len : NAN);
        }
        static const char *const names[] = {"alpha", "len", "n_x", "n_y", "n_z"};
        rc = write_level(l, a, "toksvig", level, &img, names,
                         "alpha = Toksvig-filtered Beckmann roughness sqrt(base^2 + 2 (1 - len)/len), len = |average "
                         "unit normal|, n = average normal / len");
    }
    free(img.pixels);
    return rc;
}

static int parse_args(int argc, char **argv, maps_args *a)
{
    memset(a, 0, sizeof *a);
    cli_val v[M_NOPTS];
    const char *pos[2];
    int npos;
    int prc = cli_opt_parse(&k_maps_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    static const maps_mode modes[] = {MODE_LEAN, MODE_LEADR, MODE_BUMP, MODE_TOKSVIG};
    static const char *const mode_names[] = {"lean", "leadr", "bump-roughness", "toksvig"};
    if (npos >= 1) {
        a->mode_name = pos[0];
        int m = 0;
        while (m < 4 && strcmp(pos[0], mode_names[m]) != 0)
            ++m;
        if (m == 4)
            return cli_error(k_cmd, "unknown map type '%s' (lean, leadr, bump-roughness, toksvig)", pos[0]);
        a->mode = modes[m];
    }
    a->input = npos >= 2 ? pos[1] : NULL;
    a->prefix = v[M_OUT].set ? v[M_OUT].s : NULL;
    a->green_down = v[M_GREEN].set && v[M_GREEN].i == 1;
    a->encoding = v[M_ENCODING].set ? (int)v[M_ENCODING].i : 0;
    a->tolerance = v[M_TOLERANCE].set ? v[M_TOLERANCE].d : -1.0;
    a->height = v[M_HEIGHT].set;
    a->height_scale = v[M_HEIGHT_SCALE].set ? v[M_HEIGHT_SCALE].d : 1.0;
    a->texel_size = v[M_TEXEL_SIZE].set ? v[M_TEXEL_SIZE].d : 1.0;
    a->edge = v[M_EDGE].set && v[M_EDGE].i == 1 ? MF_MAP_EDGE_CLAMP : MF_MAP_EDGE_WRAP;
    a->base_alpha = v[M_BASE_ALPHA].set ? v[M_BASE_ALPHA].d : 0.0;
    a->quiet = v[M_QUIET].set;
    a->table_formats = v[M_TABLE_FORMAT].set ? v[M_TABLE_FORMAT].s : NULL;
    int set_green = v[M_GREEN].set, set_encoding = v[M_ENCODING].set, set_tol = v[M_TOLERANCE].set;
    int set_scale = v[M_HEIGHT_SCALE].set, set_texel = v[M_TEXEL_SIZE].set, set_edge = v[M_EDGE].set;
    if (!a->mode_name)
        return cli_error(k_cmd, "needs a map type: lean, leadr, bump-roughness or toksvig (see 'mfkit maps --help')");
    if (!a->input)
        return cli_error(k_cmd, "needs an INPUT image (see 'mfkit maps --help')");
    if (!a->prefix)
        return cli_error(k_cmd, "needs --out PREFIX");
    if (a->height && (set_green || set_encoding || set_tol))
        return cli_error(k_cmd, "--green, --encoding and --normal-tolerance apply to normal maps, not with --height");
    if (!a->height && (set_scale || set_texel || set_edge))
        return cli_error(k_cmd, "--height-scale, --texel-size and --edge need --height");
    if (a->table_formats) {
        if (a->mode == MODE_TOKSVIG)
            return cli_error(k_cmd, "--table-format: toksvig filters normals, not moments (use lean, leadr or "
                                    "bump-roughness for moment_map tables)");
        const char *p = a->table_formats;
        while (*p) {
            const char *e = strchr(p, ',');
            size_t n = e ? (size_t)(e - p) : strlen(p);
            char probe[16];
            if (n == 0 || n >= sizeof a->table_ext[0] || a->ntables == 8)
                return cli_error(k_cmd, "--table-format %s: expected up to 8 comma-separated extensions "
                                        "(exr,dds,json,npy,h,glsl,hlsl,csv)", a->table_formats);
            snprintf(probe, sizeof probe, "x.%.*s", (int)n, p);
            if (mf_table_format_from_path(probe) == MF_TABLE_FORMAT_UNKNOWN)
                return cli_error(k_cmd, "--table-format: unknown table format '%.*s' (exr,dds,json,npy,h,glsl,hlsl,csv)",
                                 (int)n, p);
            for (int j = 0; j < a->ntables; ++j)
                if (!strncmp(a->table_ext[j], p, n) && a->table_ext[j][n] == '\0')
                    return cli_error(k_cmd, "--table-format: '%.*s' given twice", (int)n, p);
            snprintf(a->table_ext[a->ntables++], sizeof a->table_ext[0], "%.*s", (int)n, p);
            p += n;
            if (*p == ',' && *++p == '\0')
                return cli_error(k_cmd, "--table-format %s: a trailing comma", a->table_formats);
        }
    }
    return -1; /* parsed */
}

int cli_maps(int argc, char **argv)
{
    maps_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc >= 0)
        return rc;
    if ((rc = check_prefix_dir(a.prefix)) != 0)
        return rc;

    mf_image img;
    mf_image_info info;
    char msg[1024];
    mf_status st = mf_image_read_ex(a.input, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        cli_error(k_cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return st == MF_ERR_UNSUPPORTED ? 2 : 3;
    }
    mf_map cur = {0, 0, 0, NULL};
    if (img.width < 1 || img.height < 1) {
        rc = cli_error(k_cmd, "%s: the image has zero size (%d x %d)", a.input, img.width, img.height);
        goto done;
    }
    if (!a.height && img.channels < 3) {
        rc = cli_error(k_cmd, "%s: a normal map needs at least 3 channels (R, G, B = n.x, n.y, n.z), it has %d "
                              "(a height map? use --height)", a.input, img.channels);
        goto done;
    }
    {
        mf_map slopes = {0, 0, 0, NULL};
        if (a.height) {
            mf_map hm;
            if (mf_map_alloc(&hm, img.width, img.height, 1) != MF_OK) {
                rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
                goto done;
            }
            size_t n = (size_t)img.width * img.height;
            for (size_t t = 0; t < n; ++t)
                hm.data[t] = (double)img.pixels[t * (size_t)img.channels];
            size_t bad = 0;
            st = mf_map_slopes_from_heights(&hm, 0, a.height_scale, a.texel_size, a.edge, &slopes, &bad);
            mf_map_free(&hm);
            if (st == MF_ERR_DOMAIN) {
                rc = cli_error(k_cmd, "%s: texel (%d, %d) (column, row from the top): height is %s", a.input,
                               (int)(bad % (size_t)img.width), (int)(bad / (size_t)img.width),
                               isnan(img.pixels[bad * (size_t)img.channels]) ? "NaN" : "infinite");
                goto done;
            } else if (st != MF_OK) {
                rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
                goto done;
            }
            if (a.mode == MODE_TOKSVIG) {
                rc = normals_from_slopes(&slopes, &cur);
                mf_map_free(&slopes);
                if (rc)
                    goto done;
            }
        } else {
            mf_map normals;
            if ((rc = decode_normals(&a, &img, info.pixel_type, &normals)) != 0)
                goto done;
            if (a.mode == MODE_TOKSVIG) {
                cur = normals;
            } else {
                size_t bad = 0;
                st = mf_map_slopes_from_normals(&normals, &slopes, &bad);
                mf_map_free(&normals);
                if (st != MF_OK) {
                    rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
                    goto done;
                }
            }
        }
        if (a.mode != MODE_TOKSVIG) {
            st = mf_map_moments_from_slopes(&slopes, &cur);
            mf_map_free(&slopes);
            if (st != MF_OK) {
                rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
                goto done;
            }
        }
    }
    mf_image_free(&img);

    if (a.ntables) { /* the table files' temporary directory, beside the outputs */
        const char *slash = strrchr(a.prefix, '/');
        size_t dl = slash ? (size_t)(slash - a.prefix) + 1 : 0, n = dl + 64;
        a.table_dir = malloc(n);
        if (!a.table_dir) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
            goto done;
        }
        snprintf(a.table_dir, n, "%.*s.mfkit_maps_tables.tmp%ld", (int)dl, a.prefix, (long)getpid());
        if (mkdir(a.table_dir, 0700) != 0) {
            rc = CLI_EXIT_IO, cli_error(k_cmd, "--out %s: cannot create the temporary directory %s: %s", a.prefix,
                                        a.table_dir, strerror(errno));
            free(a.table_dir);
            a.table_dir = NULL;
            goto done;
        }
    }
    {
        out_list files = {NULL, 0, 0};
        const int levels = mf_map_mip_count(cur.width, cur.height);
        const int show = !a.quiet && isatty(fileno(stderr));
        cli_buf b = {0};
        for (int k = 0; k < levels && rc == 0; ++k) {
            if (show)
                fprintf(stderr, "\rmfkit maps: level %d/%d (%d x %d)   %s", k + 1, levels, cur.width, cur.height,
                        k + 1 == levels ? "\n" : "");
            int first = files.n;
            rc = emit_level(&files, &a, &cur, k);
            if (rc == 0 && a.ntables)
                rc = write_level_tables(&files, &a, &cur, k);
            for (int f = first; rc == 0 && f < files.n; ++f)
                cli_buf_printf(&b, "%s: level %d, %d x %d\n", files.f[f].path, k, cur.width, cur.height);
            if (rc == 0 && k + 1 < levels) {
                mf_map next;
                st = mf_map_box_downsample(&cur, &next);
                mf_map_free(&cur);
                cur = next;
                if (st != MF_OK)
                    rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
            }
        }
        if (rc == 0 && (st = mf_io_atomic_commit_all(files.f, (size_t)files.n, msg, sizeof msg)) != MF_OK)
            rc = cli_exit_code(st), cli_error(k_cmd, "%s", msg);
        if (rc != 0)
            mf_io_atomic_abort_all(files.f, (size_t)files.n);
        free(files.f);
        if (a.table_dir) {
            rmdir(a.table_dir);
            free(a.table_dir);
        }
        if (rc == 0 && cli_buf_write(&b, stdout) != 0)
            rc = CLI_EXIT_IO, cli_error(k_cmd, "stdout: write failed");
        cli_buf_free(&b);
    }
done:
    mf_map_free(&cur);
    mf_image_free(&img);
    mf_image_info_free(&info);
    return rc;
}

#endif
