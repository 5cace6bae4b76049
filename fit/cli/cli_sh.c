/*
 * cli_sh.c -- `mfkit sh project ENV [--lights FILE] [--up z|y]`: the 9 order-2 SH radiance
 * coefficients per channel of a latitude-longitude environment (mf_sh.h), plus directional
 * lights from a CSV, printed as JSON (docs/cli.md).
 * Exit code 0 on success, 2 for a usage or input error (bad option, non-finite texel, bad CSV
 * field: one stderr line naming the file, line and column), 3 for an I/O error.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include <string.h>

static const char *const k_cmd = "sh";

static const char *const k_up_names[] = {"z", "y", NULL};
enum { S_LIGHTS, S_UP, S_NOPTS };
static const cli_opt k_sh_opts[S_NOPTS] = {
    {.name = "--lights", .metavar = "FILE", .kind = CLI_OPT_STRING,
     .help = "adds directional lights from a CSV with the header dir_x,dir_y,dir_z,r,g,b: the direction towards "
             "the light in the output frame (any non-zero length), and its irradiance at normal incidence per "
             "channel (W m^-2 if ENV is in W m^-2 sr^-1; >= 0), added as c += E Y(dir) to the channels R, G, B of "
             "ENV"},
    {.name = "--up", .kind = CLI_OPT_ENUM, .choices = k_up_names, .def = "z",
     .help = "z: up = +z, phi = 0 at +x, growing towards +y; coefficients in that frame.\ny: up = +y, phi = 0 at "
             "+x, growing towards -z; coefficients in the y-up frame (the z-up projection rotated by "
             "mf_sh_rotate)"},
};
static const cli_command k_sh_cmd = {
    .name = "sh project",
    .synopsis = "ENV",
    .min_pos = 1,
    .max_pos = 1,
    .description =
        "Projects a latitude-longitude environment of radiance (EXR, HDR, TIFF, ...) onto the 9 real\n"
        "spherical harmonics of order <= 2 (R&H 2001 basis, mf_sh.h), each pixel weighted by its exact\n"
        "solid angle, and prints the coefficients of each channel (an alpha channel A is skipped) as\n"
        "JSON: L00, L1m1, L10, L11, L2m2, L2m1, L20, L21, L22 (index (l, m), 'm' for minus).\n\n"
        "Mapping: row 0 at the top touches the up pole, the last row the down pole; column 0 starts at\n"
        "phi = 0 and phi grows with the column.\n",
    .opts = k_sh_opts,
    .nopts = S_NOPTS,
    .epilog = "exit status: 0 success, 2 usage or input error, 3 I/O error\n",
};

#ifndef MFKIT_CLI_HAVE_IMAGE

int cli_sh(int argc, char **argv)
{
    return cli_opt_unavailable(&k_sh_cmd, k_cmd, "OpenImageIO", "MFKIT_WITH_OIIO", argc, argv);
}

#else

#include "mfkit/io/mf_image.h"
#include "mfkit/mfkit.h"

#include <errno.h>
#include <stdlib.h>

static void usage(FILE *f) { cli_opt_usage(&k_sh_cmd, f); }

static const char *const k_names[MF_SH_COEFFS] = {"L00", "L1m1", "L10", "L11", "L2m2", "L2m1", "L20", "L21", "L22"};

typedef struct {
    mf_vec3 dir;
    double power[3]; /* r, g, b */
} sh_light;

/* Reads the lights CSV (cli_csv_read); returns 0, or the exit code after printing the error. */
static int read_lights(const char *path, sh_light **out, int *count)
{
    static const char *const cols[6] = {"dir_x", "dir_y", "dir_z", "r", "g", "b"};
    *out = NULL;
    *count = 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return cli_error(k_cmd, "--lights %s: cannot open: %s", path, strerror(errno)), CLI_EXIT_IO;
    cli_csv csv;
    char msg[1024];
    int rc = cli_csv_read_named(f, path, &csv, msg, sizeof msg);
    fclose(f);
    if (rc != 0)
        return cli_error(k_cmd, "%s", msg), rc == CLI_CSV_IO ? CLI_EXIT_IO : CLI_EXIT_USAGE;
    for (int k = 0; k < csv.ncols && rc == 0; ++k) {
        int c = 0;
        while (c < 6 && strcmp(csv.header[k], cols[c]) != 0)
            ++c;
        if (c == 6)
            rc = cli_error(k_cmd, "%s:%ld: column %d: unknown column '%s' (the header is dir_x,dir_y,dir_z,r,g,b)",
                           path, csv.header_line, k + 1, csv.header[k]);
    }
    int idx[6];
    for (int c = 0; c < 6 && rc == 0; ++c)
        if ((idx[c] = cli_csv_column(&csv, cols[c])) < 0)
            rc = cli_error(k_cmd, "%s:%ld: missing column '%s' (the header is dir_x,dir_y,dir_z,r,g,b)", path,
                           csv.header_line, cols[c]);
    sh_light *lights = rc == 0 && csv.nrows > 0 ? malloc(sizeof *lights * (size_t)csv.nrows) : NULL;
    if (rc == 0 && csv.nrows > 0 && !lights)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
    for (int row = 0; row < csv.nrows && rc == 0; ++row) {
        char **fields = csv.cells[row];
        long lineno = csv.row_line[row];
        double v[6];
        for (int c = 0; c < 6 && rc == 0; ++c) {
            const char *s = fields[idx[c]];
            int pc = cli_parse_double(s, &v[c]);
            if (pc != 0 || !isfinite(v[c]))
                rc = cli_error(k_cmd, "%s:%ld: column %d (%s): '%s' %s", path, lineno, idx[c] + 1, cols[c], s,
                               pc == CLI_NUM_RANGE ? cli_num_error(pc) : "is not a finite number");
            else if (c >= 3 && v[c] < 0.0)
                rc = cli_error(k_cmd, "%s:%ld: column %d (%s): irradiance %s is negative", path, lineno, idx[c] + 1,
                               cols[c], s);
        }
        if (rc)
            break;
        double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (!(len > 0.0) || !isfinite(len)) {
            rc = cli_error(k_cmd, "%s:%ld: column %d (dir_x): the direction (%s, %s, %s) has zero length", path, lineno,
                           idx[0] + 1, fields[idx[0]], fields[idx[1]], fields[idx[2]]);
            break;
        }
        lights[row].dir = mf_vec3_make(v[0] / len, v[1] / len, v[2] / len);
        for (int c = 0; c < 3; ++c)
            lights[row].power[c] = v[3 + c];
    }
    int n = csv.nrows;
    cli_csv_free(&csv);
    if (rc) {
        free(lights);
        return rc;
    }
    *out = lights;
    *count = n;
    return 0;
}

static int sh_project(int argc, char **argv)
{
    cli_val ov[S_NOPTS];
    const char *pos[1];
    int npos;
    int prc = cli_opt_parse(&k_sh_cmd, argc - 1, argv + 1, ~0u, NULL, ov, pos, &npos);
    if (prc == CLI_PARSE_HELP) {
        usage(stdout);
        return 0;
    }
    if (prc)
        return prc;
    const char *env = pos[0], *lights_path = ov[S_LIGHTS].set ? ov[S_LIGHTS].s : NULL;
    int up_y = ov[S_UP].set && ov[S_UP].i == 1;

    sh_light *lights = NULL;
    int nlights = 0, rc;
    if (lights_path && (rc = read_lights(lights_path, &lights, &nlights)) != 0)
        return rc;

    mf_image img;
    mf_image_info info;
    char msg[1024];
    mf_status st = mf_image_read_ex(env, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        free(lights);
        cli_error(k_cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return cli_exit_code(st);
    }
    rc = 0;
    double *coeffs = NULL;
    int *chan = NULL, nch = 0;
    cli_buf b = {0};
    if (img.width < 1 || img.height < 1) {
        rc = cli_error(k_cmd, "%s: the image has zero size (%d x %d)", env, img.width, img.height);
        goto done;
    }
    {
        size_t n = (size_t)img.width * img.height * (size_t)img.channels;
        for (size_t t = 0; t < n; ++t)
            if (!isfinite(img.pixels[t])) {
                size_t px = t / (size_t)img.channels;
                int c = (int)(t % (size_t)img.channels);
                rc = cli_error(k_cmd, "%s: texel (%d, %d) (column, row from the top): channel %s is %s", env,
                               (int)(px % (size_t)img.width), (int)(px / (size_t)img.width),
                               info.channel_names && info.channel_names[c] ? info.channel_names[c] : "?",
                               isnan(img.pixels[t]) ? "NaN" : "infinite");
                goto done;
            }
    }
    chan = malloc(sizeof(int) * (size_t)img.channels);
    coeffs = malloc(sizeof(double) * MF_SH_COEFFS * (size_t)img.channels);
    if (!chan || !coeffs) {
        rc = CLI_EXIT_IO, cli_error(k_cmd, "out of memory");
        goto done;
    }
    for (int c = 0; c < img.channels; ++c)
        if (img.channels == 1 || !info.channel_names || strcmp(info.channel_names[c], "A") != 0)
            chan[nch++] = c;
    int rgb[3] = {-1, -1, -1};
    for (int k = 0; k < nch; ++k) {
        const char *nm = info.channel_names ? info.channel_names[chan[k]] : "";
        for (int c = 0; c < 3; ++c)
            if (!strcmp(nm, (const char *[]){"R", "G", "B"}[c]))
                rgb[c] = k;
    }
    if (nlights > 0 && (rgb[0] < 0 || rgb[1] < 0 || rgb[2] < 0)) {
        rc = cli_error(k_cmd, "%s: --lights adds r, g, b to the channels R, G, B, but the image has no %s channel",
                       env, rgb[0] < 0 ? "R" : rgb[1] < 0 ? "G" : "B");
        goto done;
    }
    /* up = +y: the z-up projection is in the map's own frame (x_l, y_l, z_l); the map's up z_l is
     * world +y, its phi = 90 deg axis y_l is world -z, x_l is world +x: world = R local with
     * the columns of R the images of the local axes.  mf_sh_rotate(in, R) gives f(R^T w). */
    const mf_mat3 r_up_y = {{{1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}, {0.0, -1.0, 0.0}}};
    for (int k = 0; k < nch; ++k) {
        double *ck = coeffs + MF_SH_COEFFS * (size_t)k;
        st = mf_sh_project_latlong(img.pixels + chan[k], img.width, img.height, img.channels,
                                   img.width * img.channels, ck);
        if (st != MF_OK) {
            rc = cli_error(k_cmd, "%s: %s", env, mf_status_str(st));
            goto done;
        }
        if (up_y)
            mf_sh_rotate(ck, r_up_y, ck);
    }
    for (int l = 0; l < nlights; ++l)
        for (int c = 0; c < 3; ++c)
            mf_sh_add_directional(coeffs + MF_SH_COEFFS * (size_t)rgb[c], lights[l].dir, lights[l].power[c]);

    cli_buf_printf(&b, "{\n  \"tool\": \"mfkit sh project\",\n  \"version\": \"%s\",\n  \"env\": ", MFKIT_VERSION);
    cli_buf_json_string(&b, env);
    cli_buf_printf(&b, ",\n  \"width\": %d,\n  \"height\": %d,\n  \"up\": \"%s\",\n", img.width, img.height,
                   up_y ? "y" : "z");
    cli_buf_printf(&b, "  \"frame\": \"%s\",\n",
                   up_y ? "y-up: row 0 at +y, column 0 at phi = 0 (+x), phi towards -z"
                        : "z-up: row 0 at +z, column 0 at phi = 0 (+x), phi towards +y");
    cli_buf_printf(&b, "  \"basis\": \"real SH without Condon-Shortley phase (Ramamoorthi-Hanrahan 2001 Eq. 3), "
                       "L_lm = integral L(w) Y_lm(w) dw\",\n");
    cli_buf_printf(&b, "  \"lights\": ");
    if (lights_path) {
        cli_buf_json_string(&b, lights_path);
        cli_buf_printf(&b, ",\n  \"light_count\": %d,\n", nlights);
    } else {
        cli_buf_printf(&b, "null,\n  \"light_count\": 0,\n");
    }
    cli_buf_printf(&b, "  \"channels\": {\n");
    for (int k = 0; k < nch; ++k) {
        cli_buf_printf(&b, "    ");
        cli_buf_json_string(&b, info.channel_names ? info.channel_names[chan[k]] : "Y");
        cli_buf_printf(&b, ": {");
        for (int i = 0; i < MF_SH_COEFFS; ++i) {
            cli_buf_printf(&b, "%s\"%s\": ", i ? ", " : "", k_names[i]);
            double v = coeffs[MF_SH_COEFFS * (size_t)k + i];
            if (isfinite(v))
                cli_buf_printf(&b, "%.17g", v);
            else
                cli_buf_printf(&b, "null");
        }
        cli_buf_printf(&b, "}%s\n", k + 1 < nch ? "," : "");
    }
    cli_buf_printf(&b, "  }\n}\n");
    if (cli_buf_write(&b, stdout) != 0)
        rc = CLI_EXIT_IO, cli_error(k_cmd, "stdout: write failed");
done:
    cli_buf_free(&b);
    free(chan);
    free(coeffs);
    free(lights);
    mf_image_free(&img);
    mf_image_info_free(&info);
    return rc;
}

int cli_sh(int argc, char **argv)
{
    for (int i = 1; i < argc; ++i)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            usage(stdout);
            return 0;
        }
    if (argc < 2)
        return cli_error(k_cmd, "needs a subcommand: project (see 'mfkit sh --help')");
    if (!strcmp(argv[1], "project"))
        return sh_project(argc - 1, argv + 1);
    return cli_error(k_cmd, "unknown subcommand '%s' (project)", argv[1]);
}

#endif
