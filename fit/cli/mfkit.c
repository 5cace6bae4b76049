/* mfkit.c -- the mfkit command line: dispatch to subcommands (docs/cli.md). */
#include "cli.h"
#include "cli_util.h"

#include <string.h>

#ifdef MFKIT_HAVE_CXX_DEPS
#include "mfkit/mf_image_oiio.h"
#endif

static void usage(FILE *f)
{
    fprintf(f,
            "usage: mfkit COMMAND [options]      (mfkit COMMAND --help for each)\n\n"
            "commands:\n"
            "  eval FUNCTION   evaluate a core function on CSV rows from stdin (NDFs, Smith, BRDFs, albedo,\n"
            "                  polygons and LTCs, GGX rectangle and proxy, filtering, SH, LEADR; the list:\n"
            "                  mfkit eval --help)\n"
            "  validate        run the property checks of the core math and print a report\n"
            "  table convert IN OUT | table info FILE\n"
            "                  convert lookup-table files (.exr .dds .json .npy -> also .h .glsl .hlsl\n"
            "                  .csv) and describe them (needs the OpenImageIO build)\n"
            "  fit ltc         fit an LTC table to a BRDF, gate it and export it (needs the Ceres build)\n"
            "  fit ggx-proxy   fit the shader formula of the GGX proxy roughness and export it (Ceres build)\n"
            "  maps lean|leadr|bump-roughness|toksvig INPUT --out PREFIX\n"
            "                  moment / roughness maps with their MIP chain from a normal or height map\n"
            "                  (needs the OpenImageIO build)\n"
            "  sh project ENV  order-2 SH coefficients of a lat-long environment as JSON (OpenImageIO build)\n\n"
            "  --version       print the version\n\n"
            "exit status: 0 success, 1 a validation check failed, 2 usage or input error, 3 I/O error\n");
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
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
    if (!strcmp(c, "eval"))
        return cli_eval(argc - 1, argv + 1);
    if (!strcmp(c, "validate"))
        return cli_validate(argc - 1, argv + 1);
    if (!strcmp(c, "table"))
        return cli_table(argc - 1, argv + 1);
    if (!strcmp(c, "fit"))
        return cli_fit(argc - 1, argv + 1);
    if (!strcmp(c, "maps"))
        return cli_maps(argc - 1, argv + 1);
    if (!strcmp(c, "sh"))
        return cli_sh(argc - 1, argv + 1);
    return cli_error(NULL, "unknown command '%s' (see 'mfkit --help')", c);
}
