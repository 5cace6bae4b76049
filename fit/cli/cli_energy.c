/*
 * cli_energy.c -- `mfkit energy KIND --out DIR`: the energy tables of mf_energy.h (kinds dfg,
 * kulla-conty, dielectric; the dielectric one on --threads workers, each (alpha, eta) column
 * computed independently and written by index, so the result does not depend on the count), computed with the accurate albedo, gated, and exported as DIR/KIND.{json,npy,h,
 * dds,exr} (.exr only in the build with the image bridge).  Needs only the core and table I/O.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_opt.h"
#include "cli_util.h"

#include "mfkit/io/mf_table_io.h"
#include "mfkit/mfkit.h"

#include <errno.h>
#include <pthread.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *const k_kinds[] = {"dfg", "kulla-conty", "dielectric", NULL};
static const char *const k_ndf[] = {"ggx", "beckmann", NULL};
static const char *const k_g2[] = {"joint", "separable", NULL};
static const char *const k_split[] = {"kulla-conty", "walk", NULL};

enum { O_OUT, O_SIZE, O_NDF, O_G2, O_NO_GATE, O_QUIET, O_THREADS, O_SPLIT, O_WALKS, O_N };
static const cli_opt k_opts[O_N] = {
    {.name = "--out", .metavar = "DIR", .kind = CLI_OPT_STRING, .required = 1,
     .help = "directory of the files KIND.json .npy .h .dds (and .exr with the image bridge); created if missing"},
    {.name = "--size", .metavar = "N", .kind = CLI_OPT_INT, .lo = 2, .hi = 1024,
     .help = "texels per axis (default: dfg 128, kulla-conty 32, dielectric 16)"},
    {.name = "--ndf", .kind = CLI_OPT_ENUM, .choices = k_ndf, .def = "ggx", .help = "the NDF"},
    {.name = "--g2", .kind = CLI_OPT_ENUM, .choices = k_g2, .def = "joint", .help = "masking-shadowing"},
    {.name = "--no-gate", .kind = CLI_OPT_FLAG, .help = "skip the gate (the files are written unchecked)"},
    {.name = "--quiet", .kind = CLI_OPT_FLAG, .help = "no progress on a terminal"},
    {.name = "--threads", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1, .hi = 256, .def = "the number of online CPUs",
     .help = "worker threads (dielectric); the result does not depend on it, bit for bit"},
    {.name = "--split", .kind = CLI_OPT_ENUM, .choices = k_split, .def = "kulla-conty",
     .help = "dielectric: kulla-conty = the 14 fields, renderers compute Kulla and Conty's split from E_avg and F_avg; "
             "walk = 6 more fields: t_walk (the random walk's transmitted fraction of its multiple scattering, both "
             "sides, with standard errors) and t_split (that pair balanced for reciprocity: the split to use)"},
    {.name = "--walks", .metavar = "N", .kind = CLI_OPT_INT, .lo = 1000, .hi = 1000000000, .def = "262144",
     .help = "walks per (alpha, eta) column and side for --split walk (se ~ 0.5 / sqrt(N x multiple-scattering share))"},
};
static const cli_command k_cmd = {
    .name = "energy",
    .synopsis = "KIND",
    .min_pos = 1,
    .max_pos = 1,
    .description = "Computes an energy table (KIND: dfg = split-sum Schlick scale and bias and the Charlie sheen\n"
                   "albedo (dfg.dds holds R scale, G bias, B Charlie), kulla-conty = E and\n"
                   "E_avg for multiple-scattering compensation) over (cos theta_o, sqrt(alpha)) at texel centres,\n"
                   "dielectric = E_r, E_t, E, E_avg of a rough dielectric over (cos theta_o, sqrt(alpha), z) with\n"
                   "eta = 1 + 2 z^2, outside (eta) and inside (1 / eta: fields _inv), Cycles' glass-table layout;\n"
                   "--split walk adds the split of the compensation closed by the random walk on the microsurface),\n"
                   "runs its gate and writes it.\n",
    .opts = k_opts,
    .nopts = O_N,
    .epilog = "exit status: 0 success, 1 the gate failed (nothing written), 2 usage error, 3 I/O error\n",
};

static void progress(void *user, long done, long total)
{
    if (*(int *)user && (done == total || done % 64 == 0))
        fprintf(stderr, "\r  %ld / %ld texels", done, total), fflush(stderr);
    if (*(int *)user && done == total)
        fprintf(stderr, "\n");
}

/* the dielectric table's workers: each takes the next column under the lock and fills it */
typedef struct {
    mf_table *t;
    long next, done, total;
    mf_status st;
    int show;
    pthread_mutex_t lock;
} diel_queue;

static void *diel_worker(void *arg)
{
    diel_queue *q = arg;
    for (;;) {
        pthread_mutex_lock(&q->lock);
        long c = q->st == MF_OK && q->next < q->total ? q->next++ : -1;
        pthread_mutex_unlock(&q->lock);
        if (c < 0)
            return NULL;
        mf_status st = mf_energy_dielectric_column(q->t, c);
        pthread_mutex_lock(&q->lock);
        if (st != MF_OK && q->st == MF_OK)
            q->st = st;
        ++q->done;
        if (q->show)
            fprintf(stderr, "\r  %ld / %ld (alpha, eta) columns", q->done, q->total), fflush(stderr);
        pthread_mutex_unlock(&q->lock);
    }
}

static mf_status dielectric_table(mf_table *t, mf_ndf_type ndf, mf_g2_form g2, int n, int threads, int show, long walks)
{
    mf_status st = walks > 0 ? mf_energy_dielectric_table_init_walk(t, ndf, g2, n, n, n, walks)
                             : mf_energy_dielectric_table_init(t, ndf, g2, n, n, n);
    if (st != MF_OK)
        return st;
    diel_queue q = {t, 0, 0, (long)n * n, MF_OK, show, PTHREAD_MUTEX_INITIALIZER};
    pthread_t th[256];
    int started = 0;
    for (; started < threads; ++started)
        if (pthread_create(&th[started], NULL, diel_worker, &q) != 0)
            break;
    if (started == 0)
        diel_worker(&q);
    for (int i = 0; i < started; ++i)
        pthread_join(th[i], NULL);
    if (show)
        fprintf(stderr, "\n");
    if (q.st != MF_OK)
        mf_table_free(t);
    return q.st;
}

int cli_energy(int argc, char **argv)
{
    cli_val v[O_N];
    const char *pos[1];
    int npos;
    int rc = cli_opt_parse(&k_cmd, argc - 1, argv + 1, ~0u, NULL, v, pos, &npos);
    if (rc == CLI_PARSE_HELP) {
        cli_opt_usage(&k_cmd, stdout);
        return 0;
    }
    if (rc)
        return rc;
    int kind = -1;
    for (int i = 0; k_kinds[i]; ++i)
        if (!strcmp(pos[0], k_kinds[i]))
            kind = i;
    if (kind < 0)
        return cli_error("energy", "unknown KIND '%s' (dfg, kulla-conty, dielectric)", pos[0]);
    const char *dir = v[O_OUT].s;
    int n = v[O_SIZE].set ? (int)v[O_SIZE].i
                          : (kind == 0 ? MF_DFG_DEFAULT_SIZE
                                       : kind == 1 ? MF_KULLA_CONTY_DEFAULT_SIZE : MF_DIELECTRIC_DEFAULT_SIZE);
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    int threads = v[O_THREADS].set ? (int)v[O_THREADS].i : (online >= 1 ? (int)(online > 256 ? 256 : online) : 1);
    mf_ndf_type ndf = v[O_NDF].set && v[O_NDF].i == 1 ? MF_NDF_BECKMANN : MF_NDF_GGX;
    mf_g2_form g2 = v[O_G2].set && v[O_G2].i == 1 ? MF_G2_SEPARABLE : MF_G2_JOINT;
    int split_walk = v[O_SPLIT].set && v[O_SPLIT].i == 1;
    long walks = v[O_WALKS].set ? (long)v[O_WALKS].i : MF_ENERGY_WALK_SPLIT_WALKS;
    if (kind != 2 && (v[O_SPLIT].set || v[O_WALKS].set))
        return cli_error("energy", "--split, --walks: only for KIND dielectric, not %s", pos[0]);
    if (v[O_WALKS].set && !split_walk)
        return cli_error("energy", "--walks %ld: needs --split walk", walks);
    struct stat sb;
    if (stat(dir, &sb) == 0 && !S_ISDIR(sb.st_mode))
        return cli_error("energy", "--out: %s: not a directory", dir);

    int show = !v[O_QUIET].set && isatty(fileno(stderr));
    mf_table t;
    mf_status st = kind == 0   ? mf_energy_dfg_table(&t, ndf, g2, n, n, progress, &show)
                   : kind == 1 ? mf_energy_kulla_conty_table(&t, ndf, g2, n, n, progress, &show)
                               : dielectric_table(&t, ndf, g2, n, threads, show, split_walk ? walks : 0);
    if (st != MF_OK)
        return cli_error("energy", "%s: the table could not be computed (%s)", pos[0], mf_status_str(st));
    if (!v[O_NO_GATE].set) {
        mf_check ch[8];
        int nc = 0;
        if (show)
            fprintf(stderr, "  gate ...\n");
        st = mf_table_kind_gate(&t, NULL, NULL, ch, 8, &nc);
        for (int i = 0; i < nc; ++i)
            printf("%-14s %s  worst %.3g (bound %g) at %s\n", ch[i].name, ch[i].passed ? "pass" : "FAIL", ch[i].worst,
                   ch[i].bound, ch[i].worst_at);
        if (st != MF_OK) {
            mf_table_free(&t);
            return st == MF_ERR_CHECK_FAILED ? (cli_error("energy", "%s: the gate failed; nothing written", pos[0]), 1)
                                             : cli_error("energy", "%s: the gate could not run", pos[0]);
        }
    }
    if (stat(dir, &sb) != 0 && mkdir(dir, 0777) != 0) {
        mf_table_free(&t);
        return cli_error("energy", "--out: %s: %s", dir, strerror(errno)), 3;
    }
    static const char *const exts[] = {"json", "npy", "h", "dds", "exr"};
    const char *stem = kind == 0 ? "dfg" : kind == 1 ? "kulla_conty" : "dielectric";
    for (int e = 0; e < 5; ++e) {
        char path[4096], msg[512];
        snprintf(path, sizeof path, "%s/%s.%s", dir, stem, exts[e]);
        mf_table_write_options wo;
        mf_table_write_options_default(&wo);
        if (kind == 0 && e == 3) {
            /* dfg.dds is the engine's texture: R scale, G bias, B Charlie, A zero (the bounds are in
             * the other files) */
            wo.dds_fields[0] = 0, wo.dds_fields[1] = 1, wo.dds_fields[2] = 4, wo.dds_fields[3] = -1;
            wo.dds_fields_set = 1;
        }
        if (kind == 2 && e == 3) {
            /* dielectric.dds: R E (outside), G E_inv (inside), B E_avg, A E_avg_inv (the 3D table as
             * its n_z slices stacked along v, as for every table of more than 2 axes) */
            wo.dds_fields[0] = 4, wo.dds_fields[1] = 11, wo.dds_fields[2] = 5, wo.dds_fields[3] = 12;
            wo.dds_fields_set = 1;
        }
        st = mf_table_write(path, &t, &wo, NULL, msg, sizeof msg);
        if (st == MF_ERR_UNSUPPORTED && e == 4)
            continue; /* EXR needs the image bridge */
        if (st != MF_OK) {
            mf_table_free(&t);
            return cli_error("energy", "%s: %s", path, msg), 3;
        }
        printf("%s\n", path);
    }
    mf_table_free(&t);
    return 0;
}
