/* cli_plot.h -- what `mfkit compare`, `mfkit table plot` and `mfkit table lobe` share: reading any
 * table file users ship (as `mfkit validate` does), an output directory whose files are removed
 * again when a command fails, and the figures, drawn by the plotting module of mfkit's Python
 * package (fit/python/mfkit/tableplot.py) from the CSV files the C library's numbers were written
 * to. */
#ifndef MF_CLI_PLOT_H
#define MF_CLI_PLOT_H

#include <stddef.h>

#include "mfkit/mf_table.h"

/* Reads the table named by arg into *t: an mfkit table file (.exr .dds .json .npy .ktx2), the
 * three.js module (.js), the reference ltc_code CSV layout (.csv), or the two textures of an LTC
 * table written as "P_1.dds+P_2.dds" (any pair mf_ltc_read_pair reads).  *half (may be NULL) is set
 * when the file stores half floats.  Returns 0, or prints one line "mfkit CMD: ..." and returns the
 * exit status. */
int cli_read_any_table(const char *cmd, const char *arg, mf_table *t, int *half);

/* The files a command writes into its output directory.  cli_outdir_open creates dir (mkdir -p);
 * cli_outdir_path gives "dir/name" and records it; cli_outdir_abort removes every recorded file (and
 * the directory when this command created it), for the "no partial output" rule. */
typedef struct {
    char dir[1024];
    int created;
    int n;
    char paths[48][1280];
} cli_outdir;

int cli_outdir_open(const char *cmd, cli_outdir *o, const char *dir); /* 0, or the exit status after one line */
const char *cli_outdir_path(cli_outdir *o, const char *name);
void cli_outdir_abort(cli_outdir *o);

/* Checks that the plotting module and its interpreter work (python3 with numpy and matplotlib),
 * before anything is written: 0, or one line "mfkit CMD: ..." and exit status 2. */
int cli_plot_available(const char *cmd);
/* Runs the plotting module with args (NULL-terminated; args[0] is its subcommand).  0 on success;
 * otherwise the module has printed one line on stderr and the exit status is returned (3). */
int cli_plot_run(const char *cmd, const char *const *args);

#endif /* MF_CLI_PLOT_H */
