/* cli.h -- the subcommands of the mfkit command line. Each returns the process exit code. */
#ifndef MF_CLI_H
#define MF_CLI_H

#include <stdio.h>

int cli_eval(int argc, char **argv);     /* argv[0] = "eval" */
int cli_energy(int argc, char **argv);   /* argv[0] = "energy"; EXR only with the image backend */
int cli_validate(int argc, char **argv); /* argv[0] = "validate"; an EXR table needs the image backend */
int cli_table(int argc, char **argv);    /* argv[0] = "table"; EXR needs the image backend */
int cli_fit(int argc, char **argv);      /* argv[0] = "fit"; usage and --list only without Ceres */
int cli_fit_aniso(int argc, char **argv); /* argv[0] = "fit", argv[1] = "ltc-aniso" (cli_fit dispatches) */
int cli_maps(int argc, char **argv);     /* argv[0] = "maps"; an error without OpenImageIO */
int cli_sh(int argc, char **argv);       /* argv[0] = "sh"; an error without OpenImageIO */
int cli_prefilter(int argc, char **argv); /* argv[0] = "prefilter"; needs Ceres and OpenImageIO */
int cli_prefilter_eval(int argc, char **argv); /* argv[0] = "prefilter-eval"; the same builds */

int cli_compare(int argc, char **argv);  /* argv[0] = "compare"; EXR needs the image backend */

#endif /* MF_CLI_H */
