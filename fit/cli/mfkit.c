/* mfkit.c -- the mfkit command line: dispatch to subcommands (docs/cli.md). */
#include "cli.h"
#include "cli_util.h"

#include <string.h>

#ifdef MFKIT_HAVE_CXX_DEPS
#include "mfkit/mf_image_oiio.h"
#endif
/* What a command's implementation links: the C core and table I/O only, or the solver and image
 * bridges too (Ceres, OpenImageIO).  A front end that must start fast links only the CLI_NEEDS_CORE
 * commands and hands the others to a second executable. */
typedef enum { CLI_NEEDS_CORE, CLI_NEEDS_FIT } cli_needs;

typedef struct {
    const char *name;
    int (*run)(int argc, char **argv); /* argv[0] = the command's name; returns the exit status */
    cli_needs needs;
    const char *summary; /* for mfkit --help: "NAME ARGS" column, then the text */
} cli_entry;

static const cli_entry k_commands[] = {
    {"eval", cli_eval, CLI_NEEDS_CORE,
     "eval FUNCTION   evaluate a core function on CSV rows from stdin (NDFs, Smith, BRDFs, albedo,\n"
     "                  polygons and LTCs, GGX rectangle and proxy, filtering, SH, LEADR; the list:\n"
     "                  mfkit eval --help)"},
    {"energy", cli_energy, CLI_NEEDS_CORE,
     "energy KIND --out DIR  DFG (dfg) or Kulla-Conty (kulla-conty) energy tables, gated and exported"},
    {"validate", cli_validate, CLI_NEEDS_CORE,
     "validate [TABLE]\n"
     "                  run the property checks of the core math, or the LTC gate on a table file"},
    {"table", cli_table, CLI_NEEDS_CORE,
     "table convert IN OUT | table info FILE\n"
     "                  convert lookup-table files (.exr .dds .json .npy -> also .h .glsl .hlsl\n"
     "                  .csv) and describe them"},
    {"fit", cli_fit, CLI_NEEDS_FIT,
     "fit ltc         fit an LTC table to a BRDF, gate it and export it (needs the Ceres build)\n"
     "  fit ggx-proxy   fit the shader formula of the GGX proxy roughness and export it (Ceres build)"},
    {"maps", cli_maps, CLI_NEEDS_FIT,
     "maps lean|leadr|bump-roughness|toksvig INPUT --out PREFIX\n"
     "                  moment / roughness maps with their MIP chain from a normal or height map\n"
     "                  (needs the OpenImageIO build)"},
    {"sh", cli_sh, CLI_NEEDS_FIT,
     "sh project ENV  order-2 SH coefficients of a lat-long environment as JSON (OpenImageIO build)"},
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

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return CLI_EXIT_USAGE;
    }
#ifdef MFKIT_HAVE_CXX_DEPS
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR tables and images */
#endif
    const char *c = argv[1];
    if (!strcmp(c, "--help") || !strcmp(c, "-h") || !strcmp(c, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(c, "--version")) {
        printf("mfkit %s%s\n", MFKIT_VERSION,
#ifdef MFKIT_HAVE_CXX_DEPS
               " (with Ceres and OpenImageIO)"
#else
               " (core only: built without Ceres and OpenImageIO)"
#endif
        );
        return 0;
    }
    for (int i = 0; i < N_COMMANDS; ++i)
        if (!strcmp(c, k_commands[i].name))
            return k_commands[i].run(argc - 1, argv + 1);
    return cli_error(NULL, "unknown command '%s' (see 'mfkit --help')", c);
}
