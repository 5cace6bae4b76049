/* cli_plot.c -- reading any shipped table, output directories without partial output, and running
 * the plotting module (cli_plot.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli_plot.h"
#include "cli_util.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mfkit/io/mf_io.h"
#include "mfkit/io/mf_ltc_export.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_table_io.h"

int cli_read_any_table(const char *cmd, const char *arg, mf_table *t, int *half)
{
    char msg[1024] = "";
    mf_status st;
    int h = 0;
    size_t len = strlen(arg);
    const char *plus = strchr(arg, '+');
    if (plus && plus != arg && plus[1]) {
        /* the two textures of one LTC table */
        char first[1024];
        if ((size_t)(plus - arg) >= sizeof first)
            return cli_error(cmd, "%s: path too long", arg);
        memcpy(first, arg, (size_t)(plus - arg));
        first[plus - arg] = '\0';
        st = mf_ltc_read_pair(first, plus + 1, t, &h, msg, sizeof msg);
    } else if (len > 3 && strcmp(arg + len - 3, ".js") == 0) {
        st = mf_ltc_read_threejs(arg, t, msg, sizeof msg);
    } else {
        mf_table_format fmt = mf_table_format_from_path(arg);
        if (fmt == MF_TABLE_FORMAT_CSV) {
            st = mf_ltc_reference_read_csv(arg, t, msg, sizeof msg);
        } else if (mf_table_format_readable(fmt)) {
            mf_table_file_info info = {0};
            st = mf_table_read(arg, t, &info, msg, sizeof msg);
            h = info.half_float;
        } else {
            return cli_error(cmd, "%s: not a readable table (.exr, .dds, .json, .npy, .ktx2, a three.js module "
                                  "<p>_three.js, a reference .csv, or a pair P_1.dds+P_2.dds)", arg);
        }
    }
    if (st != MF_OK) {
        cli_error(cmd, "%s", msg[0] ? msg : mf_status_str(st));
        return cli_exit_code(st);
    }
    if (half)
        *half = h;
    return 0;
}

int cli_outdir_open(const char *cmd, cli_outdir *o, const char *dir)
{
    memset(o, 0, sizeof *o);
    if (strlen(dir) >= sizeof o->dir - 64)
        return cli_error(cmd, "--out %s: path too long", dir);
    strcpy(o->dir, dir);
    struct stat sb;
    o->created = stat(dir, &sb) != 0;
    char msg[1024];
    if (mf_io_make_dirs(dir, msg, sizeof msg) != MF_OK)
        return cli_error(cmd, "--out %s", msg), CLI_EXIT_IO;
    return 0;
}

const char *cli_outdir_path(cli_outdir *o, const char *name)
{
    if (o->n >= (int)(sizeof o->paths / sizeof o->paths[0]))
        return NULL;
    char *p = o->paths[o->n++];
    size_t dl = strlen(o->dir), nl = strlen(name);
    if (dl + 1 + nl >= sizeof o->paths[0])
        nl = sizeof o->paths[0] - dl - 2; /* o->dir is at most 960 bytes (cli_outdir_open) */
    memcpy(p, o->dir, dl);
    p[dl] = '/';
    memcpy(p + dl + 1, name, nl);
    p[dl + 1 + nl] = '\0';
    return p;
}

void cli_outdir_abort(cli_outdir *o)
{
    for (int i = 0; i < o->n; ++i)
        remove(o->paths[i]);
    o->n = 0;
    if (o->created)
        rmdir(o->dir); /* only when empty: a file someone else put there stays */
}

/* ---- the plotting module ------------------------------------------------------------------- */

/* The interpreter: $MFKIT_PYTHON, else Debian's /usr/bin/python3 (the one with python3-numpy and
 * python3-matplotlib; a python3 first on PATH may be a separate build without them). */
static const char *python_path(void)
{
    const char *p = getenv("MFKIT_PYTHON");
    return p && *p ? p : "/usr/bin/python3";
}

/* The module tableplot.py: beside the Python package of the build tree or of the install tree,
 * found relative to this executable (MFKIT_CLI_PY_BUILD_REL, MFKIT_CLI_PY_INSTALL_REL: set per
 * executable in fit/CMakeLists.txt). */
static int find_module(char *out, size_t size)
{
    char self[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0 || (size_t)n >= sizeof self - 1)
        return -1;
    self[n] = '\0';
    char *slash = strrchr(self, '/');
    if (!slash)
        return -1;
    *slash = '\0';
    const char *rel[2] = {MFKIT_CLI_PY_BUILD_REL, MFKIT_CLI_PY_INSTALL_REL};
    for (int i = 0; i < 2; ++i) {
        snprintf(out, size, "%s/%s/tableplot.py", self, rel[i]);
        if (access(out, R_OK) == 0)
            return 0;
    }
    return -1;
}

/* Runs python module cmd args...; the module's stdout is dropped (it writes files only); returns
 * its exit status, 127 when the interpreter could not be started. */
static int run_module(const char *cmd, const char *module, const char *const *args)
{
    const char *py = python_path();
    const char *argv[64];
    int k = 0;
    argv[k++] = py;
    argv[k++] = module;
    argv[k++] = "--cmd";
    argv[k++] = cmd;
    for (int i = 0; args[i] && k < 63; ++i)
        argv[k++] = args[i];
    argv[k] = NULL;
    fflush(NULL);
    pid_t pid = fork();
    if (pid < 0)
        return 127;
    if (pid == 0) {
        FILE *dn = freopen("/dev/null", "w", stdout);
        (void)dn;
        execv(py, (char *const *)argv);
        _exit(127);
    }
    int status;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR)
            return 127;
    if (WIFEXITED(status))
        return WEXITSTATUS(status);
    return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

int cli_plot_available(const char *cmd)
{
    char module[PATH_MAX + 64];
    if (find_module(module, sizeof module) != 0)
        return cli_error(cmd, "the plotting module tableplot.py is not installed beside mfkit (looked in %s and %s "
                              "relative to the executable)", MFKIT_CLI_PY_BUILD_REL, MFKIT_CLI_PY_INSTALL_REL);
    const char *args[] = {"check", NULL};
    int rc = run_module(cmd, module, args);
    if (rc == 127)
        return cli_error(cmd, "%s: cannot run it (plots need python3 with numpy and matplotlib: apt-get install "
                              "python3-numpy python3-matplotlib, or set MFKIT_PYTHON)", python_path());
    return rc ? CLI_EXIT_USAGE : 0; /* the module has said what is missing */
}

int cli_plot_run(const char *cmd, const char *const *args)
{
    char module[PATH_MAX + 64];
    if (find_module(module, sizeof module) != 0)
        return cli_error(cmd, "the plotting module tableplot.py is not installed beside mfkit"), CLI_EXIT_IO;
    int rc = run_module(cmd, module, args);
    if (rc == 127)
        return cli_error(cmd, "%s: cannot run it", python_path()), CLI_EXIT_IO;
    return rc ? CLI_EXIT_IO : 0;
}
