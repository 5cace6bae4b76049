/* mfkit.c -- the mfkit command line: dispatch to subcommands (docs/cli.md). */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_util.h"

#include <string.h>

/*
 * One set of CLI sources, compiled twice (fit/CMakeLists.txt):
 *   MFKIT_CLI_FRONT        bin/mfkit, pure C: links mfkit and mfkit_io only, so it starts in a few
 *                          milliseconds.  It runs the commands that need neither Ceres nor
 *                          OpenImageIO itself and execs mfkit-full for the others.
 *   (not MFKIT_CLI_FRONT)  libexec/mfkit/mfkit-full: the bridges the configuration built
 *                          (MFKIT_CLI_HAVE_SOLVER, MFKIT_CLI_HAVE_IMAGE); runs every command.
 * MFKIT_CLI_WITH_CERES / MFKIT_CLI_WITH_OIIO are the configure options (0 or 1) in both.
 */
#if !defined(MFKIT_CLI_FRONT) && defined(MFKIT_CLI_HAVE_IMAGE)
#include "mfkit/fit/mf_image_oiio.h"
#endif
#include "mfkit/io/mf_table_io.h"

#ifdef MFKIT_CLI_FRONT
#include <errno.h>
#include <limits.h>
#include <unistd.h>
#endif

/* What a command needs beyond the core and table I/O, as a set of bits. */
enum { CLI_NEEDS_CORE = 0, CLI_NEEDS_IMAGE = 1, CLI_NEEDS_SOLVER = 2 };

typedef struct {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] = the command's name; returns the exit status */
    /* What this invocation needs (argv[0] = the command's name).  Erring towards more only costs
     * start-up time (mfkit-full runs every command); erring towards less would fail. */
    unsigned (*needs)(int argc, char **argv);
    const char *summary; /* for mfkit --help: "NAME ARGS" column, then the text */
} cli_entry;

static int has_arg(int argc, char **argv, const char *a, const char *b)
{
    for (int i = 1; i < argc; ++i)
        if (!strcmp(argv[i], a) || (b && !strcmp(argv[i], b)))
            return 1;
    return 0;
}

static unsigned needs_core(int argc, char **argv)
{
    (void)argc, (void)argv;
    return CLI_NEEDS_CORE;
}

/* validate TABLE, table convert IN OUT, table info FILE: an EXR argument needs the image backend
 * (every other table format is plain C).  Any argument counts, so an option's value that ends in
 * .exr also sends the command to mfkit-full, which handles it all the same. */
static unsigned needs_exr_args(int argc, char **argv)
{
    for (int i = 1; i < argc; ++i)
        if (argv[i][0] != '-' && mf_table_format_from_path(argv[i]) == MF_TABLE_FORMAT_EXR)
            return CLI_NEEDS_IMAGE;
    return CLI_NEEDS_CORE;
}

/* validate TABLE: as needs_exr_args, and the solver where the build has it: the neighbour check
 * refits its candidate texels of a table mfkit's fitter made (mf_ltc_gate.h) */
static unsigned needs_validate(int argc, char **argv)
{
    unsigned n = needs_exr_args(argc, argv);
    if (MFKIT_CLI_WITH_CERES && !has_arg(argc, argv, "--help", "-h"))
        for (int i = 1; i < argc; ++i)
            if (argv[i][0] != '-') /* a table (or an option's value: more only costs start-up time) */
                return n | CLI_NEEDS_SOLVER;
    return n;
}

/* fit: the solver, except the usage texts and `fit ltc --list` (the model registry) */
static unsigned needs_fit(int argc, char **argv)
{
    if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))
        return CLI_NEEDS_CORE;
    if ((!strcmp(argv[1], "ltc") || !strcmp(argv[1], "ggx-proxy")) && has_arg(argc - 1, argv + 1, "--help", "-h"))
        return CLI_NEEDS_CORE;
    if (!strcmp(argv[1], "ltc") && has_arg(argc - 1, argv + 1, "--list", NULL))
        return CLI_NEEDS_CORE;
    return CLI_NEEDS_SOLVER;
}

/* maps, sh: images, except --help */
static unsigned needs_image(int argc, char **argv)
{
    return has_arg(argc, argv, "--help", "-h") ? CLI_NEEDS_CORE : CLI_NEEDS_IMAGE;
}

/* prefilter: images and the solver, except --help */
static unsigned needs_image_solver(int argc, char **argv)
{
    return has_arg(argc, argv, "--help", "-h") ? CLI_NEEDS_CORE : CLI_NEEDS_IMAGE | CLI_NEEDS_SOLVER;
}

/* energy: its tables are plain C, and it writes EXR too where the build has the image backend */
static unsigned needs_image_if_built(int argc, char **argv)
{
    return MFKIT_CLI_WITH_OIIO && !has_arg(argc, argv, "--help", "-h") ? CLI_NEEDS_IMAGE : CLI_NEEDS_CORE;
}

static const cli_entry k_commands[] = {
    {"eval", cli_eval, needs_core,
     "eval FUNCTION   evaluate a core function on CSV rows from stdin (NDFs, Smith, BRDFs, albedo,\n"
     "                  polygons and LTCs, GGX rectangle and proxy, filtering, SH, LEADR; the list:\n"
     "                  mfkit eval --help)"},
    {"energy", cli_energy, needs_image_if_built,
     "energy KIND --out DIR\n"
     "                  DFG (dfg), Kulla-Conty (kulla-conty) or rough-dielectric (dielectric) energy\n"
     "                  tables, gated and exported"},
    {"validate", cli_validate, needs_validate,
     "validate [TABLE]\n"
     "                  run the property checks of the core math, or the LTC gate on a table file"},
    {"table", cli_table, needs_exr_args,
     "table convert IN OUT | table info FILE\n"
     "                  convert lookup-table files (.exr .dds .json .npy -> also .h .glsl .hlsl\n"
     "                  .csv) and describe them\n"
     "  table plot TABLE --out DIR | table lobe TABLE --at R,U --out DIR\n"
     "                  heat maps of every field; the fitted lobe beside the BRDF (needs python3 +\n"
     "                  matplotlib for the PNGs)"},
    {"compare", cli_compare, needs_exr_args,
     "compare A B     two tables of the same kind: difference maps, the polygon-shading error of both\n"
     "                  against Monte Carlo on the same lights (LTC tables), a one-line verdict"},
    {"fit", cli_fit, needs_fit,
     "fit ltc         fit an LTC table to a BRDF, gate it and export it (needs the Ceres build)\n"
     "  fit ltc-aniso   fit the 4-D anisotropic GGX LTC table, gate it and export it (Ceres build)\n"
     "  fit ggx-proxy   fit the shader formula of the GGX proxy roughness and export it (Ceres build)"},
    {"maps", cli_maps, needs_image,
     "maps lean|leadr|bump-roughness|toksvig INPUT --out PREFIX\n"
     "                  moment / roughness maps with their MIP chain from a normal or height map\n"
     "                  (needs the OpenImageIO build)"},
    {"sh", cli_sh, needs_image,
     "sh project ENV  order-2 SH coefficients of a lat-long environment as JSON (OpenImageIO build)"},
    {"prefilter", cli_prefilter, needs_image_solver,
     "prefilter NORMALMAP --out DIR\n"
     "                  LTC lobes of a normal map's footprints per MIP level and view (Ceres + OpenImageIO)"},
    {"prefilter-eval", cli_prefilter_eval, needs_image_solver,
     "prefilter-eval PREFILTER_DIR --out DIR\n"
     "                  shading error of the prefiltered lobes against Monte Carlo ground truth, beside\n"
     "                  naive, Toksvig and LEADR (Ceres + OpenImageIO)"},
};
#define N_COMMANDS ((int)(sizeof k_commands / sizeof k_commands[0]))

static void usage(FILE *f)
{
    fprintf(f, "usage: mfkit COMMAND [options]      (mfkit COMMAND --help for each)\n\ncommands:\n");
    for (int i = 0; i < N_COMMANDS; ++i)
        fprintf(f, "  %s\n", k_commands[i].summary);
    fprintf(f, "\n  --version       print the version\n\n"
               "exit status: 0 success, 1 a validation check failed, 2 usage or input error, 3 I/O error,\n"
               "4 fit failure, 130 interrupted\n");
}

#ifdef MFKIT_CLI_FRONT
/* Runs mfkit-full with the same argv (stdin, stdout, stderr and the exit status pass through
 * exec unchanged), or says in one line why it cannot; returns only on failure. */
static int run_full(const cli_entry *e, unsigned needs, int argc, char **argv)
{
    const char *cmd = e->name;
    if ((needs & CLI_NEEDS_SOLVER) && !MFKIT_CLI_WITH_CERES)
        return cli_error(cmd, "needs the Ceres build (configured with MFKIT_WITH_CERES=OFF)");
    if ((needs & CLI_NEEDS_IMAGE) && !MFKIT_CLI_WITH_OIIO) {
        for (int i = 2; e->needs == needs_exr_args && i < argc; ++i) /* name the EXR file */
            if (argv[i][0] != '-' && mf_table_format_from_path(argv[i]) == MF_TABLE_FORMAT_EXR)
                return cli_error(cmd, "%s: EXR needs the OpenImageIO build (configured with MFKIT_WITH_OIIO=OFF)",
                                 argv[i]);
        return cli_error(cmd, "needs the OpenImageIO build (configured with MFKIT_WITH_OIIO=OFF)");
    }
    char self[PATH_MAX], full[PATH_MAX + sizeof MFKIT_CLI_FULL_RELPATH + 1];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0 || (size_t)n >= sizeof self - 1)
        return cli_error(cmd, "/proc/self/exe: %s (needed to find mfkit-full)", n < 0 ? strerror(errno) : "path too long");
    self[n] = '\0';
    char *slash = strrchr(self, '/');
    if (!slash)
        return cli_error(cmd, "/proc/self/exe: not an absolute path: %s", self);
    *slash = '\0';
    snprintf(full, sizeof full, "%s/%s", self, MFKIT_CLI_FULL_RELPATH);
    /* validate TABLE asks for mfkit-full only for its refits: without it (mfkit installed alone),
     * the front validates as before, with the fitter-free neighbour check */
    if (e->needs == needs_validate && !(needs & CLI_NEEDS_IMAGE) && access(full, X_OK) != 0)
        return e->run(argc - 1, argv + 1);
    fflush(NULL);
    execv(full, argv);
    return cli_error(cmd, "%s: %s (the Ceres and OpenImageIO commands run in mfkit-full, installed with mfkit)", full,
                     strerror(errno));
}
#endif

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return CLI_EXIT_USAGE;
    }
#if !defined(MFKIT_CLI_FRONT) && defined(MFKIT_CLI_HAVE_IMAGE)
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR tables and images */
#endif
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h") || !strcmp(c, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(c, "--version")) {
        printf("mfkit %s (Ceres: %s, OpenImageIO: %s)\n", MFKIT_VERSION, MFKIT_CLI_WITH_CERES ? "yes" : "no",
               MFKIT_CLI_WITH_OIIO ? "yes" : "no");
        return 0;
    }
    for (int i = 0; i < N_COMMANDS; ++i) {
        if (strcmp(c, k_commands[i].name))
            continue;
#ifdef MFKIT_CLI_FRONT
        unsigned needs = k_commands[i].needs(argc - 1, argv + 1);
        if (needs != CLI_NEEDS_CORE)
            return run_full(&k_commands[i], needs, argc, argv);
#endif
        return k_commands[i].run(argc - 1, argv + 1);
    }
    return cli_error(NULL, "unknown command '%s' (see 'mfkit --help')", c);
}
