/* cli.h -- the subcommands of the mfkit command line. Each returns the process exit code. */
#ifndef MF_CLI_H
#define MF_CLI_H

#include <stdio.h>

int cli_eval(int argc, char **argv);
int cli_energy(int argc, char **argv);   /* argv[0] = "energy" */     /* argv[0] = "eval" */
int cli_validate(int argc, char **argv); /* argv[0] = "validate" */
int cli_table(int argc, char **argv);    /* argv[0] = "table"; an error without OpenImageIO */
int cli_fit(int argc, char **argv);      /* argv[0] = "fit"; an error without Ceres/OpenImageIO */
int cli_maps(int argc, char **argv);     /* argv[0] = "maps"; an error without OpenImageIO */
int cli_sh(int argc, char **argv);       /* argv[0] = "sh"; an error without OpenImageIO */

#endif /* MF_CLI_H */
