/*
 * study_aniso_oracle.c -- how low can ANY single-LTC table go on the anisotropic benchmark?
 * (issue 12; a study, not a test)
 *
 *   build-dir/analysis/study_aniso_oracle [--points N] [--samples M] [--threads T] [--perturbed K]
 *                                         [--train N [--train-perturbed K]]
 *                                         [--objective abs|relative | --table FILE] [--out FILE.csv]
 *                                         PUBLISHED.npy
 * Measured (docs/validation.md): --points 60 --threads 2 --perturbed 3 --train 96
 * --train-perturbed 1: 321 s of CPU.
 *
 * The cases are exactly analysis/bench_ltc_aniso.c's (bench_ltc_aniso_common.h): the same N
 * off-grid points (default 60), their 12 random quads, the same Monte Carlo truth (M samples,
 * default 2^18) and exact albedo.  For each point it finds the single LTC (a 3x3 matrix, 7 free
 * parameters: scale and the rotation about z of the cosine do not change the lobe
 * [Kt, Heitz, Dupuy, Narayanan 2022, Sec. 4.2]) that minimises, IN-SAMPLE on that point's own
 * 12 quads and their Monte Carlo truth, with magnitude = the exact albedo (the benchmark's shape
 * error):
 *   (a) the mean absolute error   mean_k |A E(P_k; M) - I_k|,
 *   (b) the mean relative error   mean_k |A E(P_k; M) - I_k| / max(I_k, 0.01 A),
 * the benchmark's own measures (abench_abs_err, abench_rel_err), not a least-squares proxy.
 *
 * Why this bounds every table: a shader interpolates the table's matrices at the point and
 * shades with that ONE matrix, so the interpolated matrix of any single-lobe table (mfkit's, the
 * published one, any objective, any size) is one candidate of the minimisation; its error at
 * that point on those quads is >= the oracle's, and so is its mean over the points.  Caveats
 * (printed): the minimiser may miss the global minimum (several starts, their agreement is
 * printed), and the truth is a Monte Carlo estimate (its standard error is printed; fitting the
 * noise can only lower the in-sample minimum, by at most the mean |noise|, so the bound is
 * corrected by it).
 *
 * The chart.  Each start M0 is brought to M0 = R_m M' with m the unit last column of M0, R_m the
 * minimal rotation taking z to m, and M' = [[a, 0, b], [c, d, e], [f, g, 1]] after a rotation
 * about z and a scale (the gauge of mf_ltcfit_aniso.h); x = (a, b, c, d, e, f, g) is searched.
 * Any M whose last column has a positive component along m is reached, i.e. the whole
 * neighbourhood of the start (every start's chart is its own).
 *
 * The minimiser.  Nelder-Mead [Nelder & Mead 1965; coefficients 1, 2, 1/2, 1/2 as in Lagarias,
 * Reeds, Wright & Wright 1998, Sec. 2] with restarts from the best vertex (a fresh simplex of half
 * the previous size) until a restart gains less than 1e-9 relatively, on a smoothed objective
 * (|r| -> sqrt(r^2 + eps^2) - eps, eps = 0.3 and 0.03 times the start's mean error) and then on
 * the exact one (eps = 0): the L1-type objective is not differentiable where a residual is 0, and
 * its minimum typically lies on such kinks.  Starts: mfkit's interpolated table matrix, the
 * published table's, a fit made at the point by mf_ltcfit_aniso_entry_fit (Ceres, least squares
 * over the fitter's 96 lights), the fitter's closed-form start after one solver step, 3 K perturbed
 * copies (K of each of the first three; default K = 6; relative perturbations up to 30 %), and for
 * (b) also the best of (a), and (a) once more from the best of (b).  A start "agrees" when its
 * final value is within 1 % of the point's best.
 *
 * The in-sample bound is loose: 7 parameters nearly interpolate 12 quads.  --train N therefore
 * also fits each point to N OTHER quads of the benchmark's distribution (the same generator on the
 * stream 2^40 + i; truth likewise), with the unperturbed starts and 3 K' (--train-perturbed K',
 * default 1) perturbed ones, and reports (1) its in-sample minimum there beside the tables' means
 * on the same quads: on average at most the smallest EXPECTED error over random quads of any
 * single LTC at the point (E[min] <= min E), hence a lower bound in expectation for every table;
 * (2) its error on the benchmark's quads (out of sample).
 *
 * Output: the means over all points x 12 quads (the benchmark's pooling) of the abs and rel error
 * of mfkit's table, the published table, the fit at the point, oracle (a) and oracle (b), the
 * ratios to the published table, the Monte Carlo error, the starts' agreement; with --out, one
 * CSV row per point (provenance line first; analysis/study_header.h).
 *
 * --table FILE reads mfkit's table (e.g. the .npy of `mfkit fit ltc-aniso --out DIR`) instead of
 * fitting the default one.  --objective relative fits mfkit's table with mf_ltcfit_aniso_options.objective =
 * MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE instead of the default (the comparison of the table rows).
 */
#define _POSIX_C_SOURCE 200809L
#include "mfkit/mfkit.h"
#include "mfkit/mf_ltc_aniso_table.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/io/mf_table_io.h"

#include "bench_ltc_aniso_common.h"
#include "study_header.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define NX 7
#define OBJ_HUGE 1e30

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* ---- 3x3 helpers (row-major) ---------------------------------------------------------------- */

static void mul3(const double *a, const double *b, double *c)
{
    double r[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    memcpy(c, r, sizeof r);
}

/* The minimal rotation taking z to the unit vector m (about the axis z x m; Rodrigues):
 * R = I + K + K^2 / (1 + m.z), K the cross-product matrix of z x m = (-m.y, m.x, 0). */
static void rot_z_to(const double m[3], double r[9])
{
    double k[9] = {0, 0, m[0], 0, 0, m[1], -m[0], -m[1], 0}, k2[9];
    mul3(k, k, k2);
    double s = 1.0 / (1.0 + m[2]);
    for (int i = 0; i < 9; ++i)
        r[i] = (i % 4 == 0) + k[i] + s * k2[i];
}

/* ---- the chart ------------------------------------------------------------------------------- */

typedef struct {
    double r[9]; /* R_m */
} chart;

/* M0 -> (chart, x); 0 if M0's last column is 0 or points along -z. */
static int chart_from(const double m0[9], chart *c, double x[NX])
{
    double col[3] = {m0[2], m0[5], m0[8]};
    double n = sqrt(col[0] * col[0] + col[1] * col[1] + col[2] * col[2]);
    if (!(n > 0.0) || col[2] / n < -0.999)
        return 0;
    double m[3] = {col[0] / n, col[1] / n, col[2] / n};
    rot_z_to(m, c->r);
    double rt[9] = {c->r[0], c->r[3], c->r[6], c->r[1], c->r[4], c->r[7], c->r[2], c->r[5], c->r[8]}, mp[9];
    mul3(rt, m0, mp); /* last column (0, 0, n) up to rounding */
    double p = mp[0], q = mp[1], h = hypot(p, q);
    if (!(h > 0.0))
        return 0;
    double cs = p / h, sn = q / h;
    for (int i = 0; i < 3; ++i) { /* right-multiply by the rotation about z that zeroes M'_01 */
        double u = mp[3 * i], v = mp[3 * i + 1];
        mp[3 * i] = cs * u + sn * v;
        mp[3 * i + 1] = -sn * u + cs * v;
    }
    double s = 1.0 / mp[8];
    x[0] = mp[0] * s, x[1] = mp[2] * s, x[2] = mp[3] * s, x[3] = mp[4] * s, x[4] = mp[5] * s, x[5] = mp[6] * s,
    x[6] = mp[7] * s;
    return 1;
}

static void chart_matrix(const chart *c, const double x[NX], double m[9])
{
    double mp[9] = {x[0], 0.0, x[1], x[2], x[3], x[4], x[5], x[6], 1.0};
    mul3(c->r, mp, m);
    double n = sqrt(m[2] * m[2] + m[5] * m[5] + m[8] * m[8]); /* the published normalisation */
    for (int i = 0; i < 9; ++i)
        m[i] /= n;
}

/* ---- the objective --------------------------------------------------------------------------- */

enum { OBJ_ABS = 0, OBJ_REL = 1 };
#define MAXQ 256

/* A set of quads with their truth at one point. */
typedef struct {
    int n;
    const mf_polygon *quads;
    const double *mc;
    double albedo;
} qset;

typedef struct {
    const qset *c;
    const chart *ch;
    int kind;
    double eps; /* smoothing; 0: the benchmark's measure exactly */
    long evals;
} objective;

/* Per-quad errors of the matrix m (both measures). */
static int quad_errors(const qset *c, const double m[9], double *ea, double *er)
{
    mf_ltc l;
    if (mf_ltc_init(&l, mf_ltc_matrix_general(m)) != MF_OK)
        return 0;
    for (int k = 0; k < c->n; ++k) {
        double v = c->albedo * mf_ltc_integrate_polygon(&l, &c->quads[k], MF_POLYGON_ONE_SIDED);
        if (!isfinite(v))
            return 0;
        ea[k] = abench_abs_err(v, c->mc[k]);
        er[k] = abench_rel_err(v, c->mc[k], c->albedo);
    }
    return 1;
}

static double mean_n(const double *e, int n)
{
    double s = 0.0;
    for (int k = 0; k < n; ++k)
        s += e[k];
    return s / n;
}

static double mean_q(const double *e)
{
    return mean_n(e, ABENCH_Q);
}

static double obj_eval(objective *o, const double x[NX])
{
    ++o->evals;
    double m[9], ea[MAXQ], er[MAXQ];
    chart_matrix(o->ch, x, m);
    if (!quad_errors(o->c, m, ea, er))
        return OBJ_HUGE;
    const double *e = o->kind == OBJ_ABS ? ea : er;
    double s = 0.0;
    for (int k = 0; k < o->c->n; ++k)
        s += o->eps > 0.0 ? sqrt(e[k] * e[k] + o->eps * o->eps) - o->eps : e[k];
    s /= o->c->n;
    return isfinite(s) ? s : OBJ_HUGE;
}

/* ---- Nelder-Mead ------------------------------------------------------------------------------ */

/* One Nelder-Mead run from x with initial steps step[]; x <- the best vertex, returns its value. */
static double nelder_mead(objective *o, double x[NX], const double step[NX], int max_evals)
{
    double v[NX + 1][NX], f[NX + 1];
    for (int i = 0; i <= NX; ++i) {
        memcpy(v[i], x, sizeof v[i]);
        if (i > 0)
            v[i][i - 1] += step[i - 1];
        f[i] = obj_eval(o, v[i]);
    }
    long start = o->evals;
    for (;;) {
        /* order: best first (insertion sort, stable) */
        for (int i = 1; i <= NX; ++i)
            for (int j = i; j > 0 && f[j] < f[j - 1]; --j) {
                double t = f[j];
                f[j] = f[j - 1], f[j - 1] = t;
                for (int k = 0; k < NX; ++k) {
                    double u = v[j][k];
                    v[j][k] = v[j - 1][k], v[j - 1][k] = u;
                }
            }
        if (o->evals - start >= max_evals || f[NX] - f[0] <= 1e-12 * fabs(f[0]) + 1e-300)
            break;
        double cen[NX] = {0}, xr[NX], xe[NX], xc[NX];
        for (int i = 0; i < NX; ++i)
            for (int k = 0; k < NX; ++k)
                cen[k] += v[i][k] / NX;
        for (int k = 0; k < NX; ++k)
            xr[k] = cen[k] + (cen[k] - v[NX][k]);
        double fr = obj_eval(o, xr);
        if (fr < f[0]) {
            for (int k = 0; k < NX; ++k)
                xe[k] = cen[k] + 2.0 * (cen[k] - v[NX][k]);
            double fe = obj_eval(o, xe);
            if (fe < fr)
                memcpy(v[NX], xe, sizeof xe), f[NX] = fe;
            else
                memcpy(v[NX], xr, sizeof xr), f[NX] = fr;
            continue;
        }
        if (fr < f[NX - 1]) {
            memcpy(v[NX], xr, sizeof xr), f[NX] = fr;
            continue;
        }
        int outside = fr < f[NX];
        for (int k = 0; k < NX; ++k)
            xc[k] = outside ? cen[k] + 0.5 * (xr[k] - cen[k]) : cen[k] + 0.5 * (v[NX][k] - cen[k]);
        double fc = obj_eval(o, xc);
        if (outside ? fc <= fr : fc < f[NX]) {
            memcpy(v[NX], xc, sizeof xc), f[NX] = fc;
            continue;
        }
        for (int i = 1; i <= NX; ++i) { /* shrink towards the best */
            for (int k = 0; k < NX; ++k)
                v[i][k] = v[0][k] + 0.5 * (v[i][k] - v[0][k]);
            f[i] = obj_eval(o, v[i]);
        }
    }
    memcpy(x, v[0], sizeof v[0]);
    return f[0];
}

/* The staged, restarted minimisation of objective kind from the matrix m0; m <- the best matrix,
 * returns its exact (eps = 0) value; OBJ_HUGE if m0 has no chart. */
static double minimise(const qset *c, int kind, const double m0[9], double m[9], long *evals)
{
    chart ch;
    double x[NX];
    if (!chart_from(m0, &ch, x))
        return OBJ_HUGE;
    objective o = {c, &ch, kind, 0.0, 0};
    double f0 = obj_eval(&o, x);
    if (f0 >= OBJ_HUGE)
        return OBJ_HUGE;
    const double eps_rel[3] = {0.3, 0.03, 0.0};
    double scale = 0.5 * (fabs(x[0]) + fabs(x[3]));
    for (int stage = 0; stage < 3; ++stage) {
        o.eps = eps_rel[stage] * f0;
        double step[NX], h = 0.1, f = obj_eval(&o, x);
        for (int restart = 0; restart < 12; ++restart, h *= 0.5) {
            for (int k = 0; k < NX; ++k)
                step[k] = h * fmax(fabs(x[k]), 0.1 * scale);
            double fn = nelder_mead(&o, x, step, 3000);
            double gain = f - fn;
            f = fn;
            if (restart > 0 && gain <= 1e-9 * fabs(f))
                break;
        }
    }
    o.eps = 0.0;
    double f = obj_eval(&o, x);
    chart_matrix(&ch, x, m);
    *evals += o.evals;
    return f;
}

/* ---- per point ------------------------------------------------------------------------------- */

enum { START_MFKIT, START_PUBLISHED, START_FIT, START_CLOSED, START_FIXED };
#define MAX_STARTS 64

/* One objective's multistart at one point. */
typedef struct {
    double m[9];     /* the best LTC */
    double best;     /* its value */
    int starts;      /* starts that ran */
    int agree;       /* of them, within 1 % of the best */
    int agree_fixed; /* of the 4 unperturbed ones, within 1 % of the best */
} oracle;

typedef struct {
    abench_case c;
    int ok;
    double m_mfkit[9], m_pub[9], m_fit[9];
    int have_fit;
    /* per-quad errors (abs, rel) on the benchmark's quads of the table rows and the oracles */
    double ea_mfkit[ABENCH_Q], er_mfkit[ABENCH_Q], ea_pub[ABENCH_Q], er_pub[ABENCH_Q];
    double ea_fit[ABENCH_Q], er_fit[ABENCH_Q];
    double ea_oa[ABENCH_Q], er_oa[ABENCH_Q], ea_ob[ABENCH_Q], er_ob[ABENCH_Q];
    oracle oa, ob;
    /* --train N: the oracles fitted to N other quads of the same distribution (tra, trb), their
     * in-sample minima there, and their errors on the benchmark's quads (out of sample);
     * the tables' means on the training quads for comparison */
    int ntrain;
    oracle tra, trb;
    double ea_ta[ABENCH_Q], er_ta[ABENCH_Q], ea_tb[ABENCH_Q], er_tb[ABENCH_Q];
    double train_mfkit_abs, train_mfkit_rel, train_pub_abs, train_pub_rel;
    double train_se_abs, train_se_rel;
    long evals;
} point_result;

typedef struct {
    const mf_brdf_model *ggx;
    const mf_table *t;
    const float *pub;
    const mf_ltcfit_aniso_options *o;
    int samples, perturbed, npoints, train, train_perturbed;
    point_result *res;
    int next;
    pthread_mutex_t lock;
} job;

static void perturb(mf_pcg32 *rng, const double m0[9], double m[9])
{
    chart ch;
    double x[NX];
    if (!chart_from(m0, &ch, x)) {
        memcpy(m, m0, 9 * sizeof *m);
        return;
    }
    double scale = 0.5 * (fabs(x[0]) + fabs(x[3]));
    for (int k = 0; k < NX; ++k) {
        double u = 2.0 * mf_pcg32_next_double(rng) - 1.0;
        x[k] += 0.3 * u * fmax(fabs(x[k]), 0.3 * scale);
    }
    chart_matrix(&ch, x, m);
}

/* Objective kind on the quads c from the 4 unperturbed starts fixed[] (have[]), 3 K perturbed
 * copies of the first three (stream `stream`), and `extra` (may be NULL) as one more start. */
static void run_oracle(const qset *c, int kind, double fixed[START_FIXED][9], const int have_fixed[START_FIXED],
                       int k_pert, uint64_t stream, const double *extra, oracle *out, long *evals)
{
    int n = START_FIXED + 3 * k_pert;
    double(*starts)[9] = calloc((size_t)n + 1, sizeof *starts);
    int have[MAX_STARTS + 1] = {0};
    double vals[MAX_STARTS + 1];
    memcpy(starts, fixed, START_FIXED * sizeof *starts);
    memcpy(have, have_fixed, START_FIXED * sizeof *have);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 0x6f7261636c65ull, stream);
    for (int s = START_FIXED; s < n; ++s) {
        perturb(&rng, starts[(s - START_FIXED) % 3], starts[s]);
        have[s] = have[(s - START_FIXED) % 3];
    }
    if (extra) {
        memcpy(starts[n], extra, sizeof starts[0]);
        have[n++] = 1;
    }
    out->best = OBJ_HUGE;
    memcpy(out->m, fixed[START_MFKIT], sizeof out->m);
    for (int s = 0; s < n; ++s) {
        vals[s] = OBJ_HUGE;
        if (!have[s])
            continue;
        double m[9];
        vals[s] = minimise(c, kind, starts[s], m, evals);
        if (vals[s] < out->best) {
            out->best = vals[s];
            memcpy(out->m, m, sizeof m);
        }
    }
    out->starts = out->agree = out->agree_fixed = 0;
    for (int s = 0; s < n; ++s)
        if (vals[s] < OBJ_HUGE) {
            ++out->starts;
            out->agree += vals[s] <= 1.01 * out->best;
            out->agree_fixed += s < START_FIXED && vals[s] <= 1.01 * out->best;
        }
    free(starts);
}

static void run_point(job *j, int i)
{
    point_result *r = &j->res[i];
    abench_case *c = &r->c;
    double p[4];
    memcpy(p, c->p, sizeof p);
    r->ok = 0;
    if (!abench_case_make(j->ggx, p, i, j->samples, c))
        return;
    qset qb = {ABENCH_Q, c->quads, c->mc, c->albedo};
    double mag;
    if (mf_ltc_aniso_lookup(j->t, p[0], p[1], p[2], p[3], r->m_mfkit, &mag, NULL) != MF_OK)
        return;
    abench_published(j->pub, p, r->m_pub);
    mf_ltcfit_aniso_entry fe;
    r->have_fit = mf_ltcfit_aniso_entry_fit(j->ggx, p[0], p[1], p[2], p[3], NULL, j->o, &fe) == MF_OK;
    memcpy(r->m_fit, r->have_fit ? fe.m : r->m_mfkit, sizeof r->m_fit);
    mf_ltcfit_aniso_options o1 = *j->o;
    o1.max_iterations = 1;
    mf_ltcfit_aniso_entry fc;
    int have_closed = mf_ltcfit_aniso_entry_fit(j->ggx, p[0], p[1], p[2], p[3], NULL, &o1, &fc) == MF_OK;
    if (!quad_errors(&qb, r->m_mfkit, r->ea_mfkit, r->er_mfkit) || !quad_errors(&qb, r->m_pub, r->ea_pub, r->er_pub) ||
        !quad_errors(&qb, r->m_fit, r->ea_fit, r->er_fit))
        return;
    double fixed[START_FIXED][9];
    int have[START_FIXED] = {1, 1, r->have_fit, have_closed};
    memcpy(fixed[START_MFKIT], r->m_mfkit, sizeof fixed[0]);
    memcpy(fixed[START_PUBLISHED], r->m_pub, sizeof fixed[0]);
    memcpy(fixed[START_FIT], r->m_fit, sizeof fixed[0]);
    memcpy(fixed[START_CLOSED], have_closed ? fc.m : r->m_mfkit, sizeof fixed[0]);

    /* in-sample on the benchmark's quads: (a), then (b) with (a)'s best as one more start, then
     * (a) once more from (b)'s best */
    run_oracle(&qb, OBJ_ABS, fixed, have, j->perturbed, (uint64_t)i, NULL, &r->oa, &r->evals);
    run_oracle(&qb, OBJ_REL, fixed, have, j->perturbed, (uint64_t)i, r->oa.m, &r->ob, &r->evals);
    double m2[9], f2 = minimise(&qb, OBJ_ABS, r->ob.m, m2, &r->evals);
    if (f2 < r->oa.best) {
        r->oa.best = f2;
        memcpy(r->oa.m, m2, sizeof m2);
    }
    if (!quad_errors(&qb, r->oa.m, r->ea_oa, r->er_oa) || !quad_errors(&qb, r->ob.m, r->ea_ob, r->er_ob))
        return;

    r->ntrain = 0;
    if (j->train > 0) {
        /* N quads of the benchmark's distribution from another stream (2^40 + i): the even
         * indices of mf_ltc_gate_random_polygons_params, as the benchmark's; truth as the
         * benchmark's (seed 9) on that stream */
        int nt = j->train;
        uint64_t st = (1ull << 40) + (uint64_t)i;
        mf_brdf_params prm = {p[0], p[1]};
        mf_vec3 wo = mf_vec3_make(sin(p[2]) * cos(p[3]), sin(p[2]) * sin(p[3]), cos(p[2]));
        mf_polygon *polys = malloc(sizeof *polys * 2 * (size_t)nt), *tq = malloc(sizeof *tq * (size_t)nt);
        double *mc = malloc(sizeof *mc * 2 * (size_t)nt), *se = mc + nt, ea[MAXQ], er[MAXQ];
        mf_ltc_gate_random_polygons_params(j->ggx, &prm, wo, 5, st, 2 * nt, polys);
        for (int k = 0; k < nt; ++k)
            tq[k] = polys[2 * k];
        if (mf_ltc_gate_polygon_mc_params(j->ggx, &prm, wo, tq, nt, j->samples, 9, st, mc, se, NULL) == MF_OK) {
            qset qt = {nt, tq, mc, c->albedo};
            r->train_se_abs = r->train_se_rel = 0.0;
            for (int k = 0; k < nt; ++k) {
                r->train_se_abs += se[k] / nt;
                r->train_se_rel += se[k] / fmax(mc[k], 0.01 * c->albedo) / nt;
            }
            int ok = quad_errors(&qt, r->m_mfkit, ea, er);
            r->train_mfkit_abs = mean_n(ea, nt), r->train_mfkit_rel = mean_n(er, nt);
            ok = ok && quad_errors(&qt, r->m_pub, ea, er);
            r->train_pub_abs = mean_n(ea, nt), r->train_pub_rel = mean_n(er, nt);
            /* starts: the 4 unperturbed and perturbed ones only (nothing fitted to the benchmark's quads) */
            run_oracle(&qt, OBJ_ABS, fixed, have, j->train_perturbed, st, NULL, &r->tra, &r->evals);
            run_oracle(&qt, OBJ_REL, fixed, have, j->train_perturbed, st, r->tra.m, &r->trb, &r->evals);
            if (ok && r->tra.best < OBJ_HUGE && r->trb.best < OBJ_HUGE &&
                quad_errors(&qb, r->tra.m, r->ea_ta, r->er_ta) && quad_errors(&qb, r->trb.m, r->ea_tb, r->er_tb))
                r->ntrain = nt;
        }
        free(polys);
        free(tq);
        free(mc);
    }
    r->ok = 1;
}

static void *worker(void *arg)
{
    job *j = arg;
    for (;;) {
        pthread_mutex_lock(&j->lock);
        int i = j->next++;
        pthread_mutex_unlock(&j->lock);
        if (i >= j->npoints)
            return NULL;
        run_point(j, i);
    }
}

/* ---- reporting ------------------------------------------------------------------------------- */

typedef struct {
    double sa, sr;
    int n;
} pooled;

static void pool(pooled *p, const double *ea, const double *er)
{
    for (int k = 0; k < ABENCH_Q; ++k)
        p->sa += ea[k], p->sr += er[k], ++p->n;
}

static void row(const char *name, const pooled *p, const pooled *pub)
{
    printf("%-34s abs mean %.6f (%.3fx published)   rel mean %.5f (%.3fx published)\n", name, p->sa / p->n,
           (p->sa / p->n) / (pub->sa / pub->n), p->sr / p->n, (p->sr / p->n) / (pub->sr / pub->n));
}

static int usage(void)
{
    fprintf(stderr, "usage: study_aniso_oracle [--points N] [--samples M] [--threads T] [--perturbed K] "
                    "[--objective abs|relative | --table FILE] [--out FILE.csv] PUBLISHED.npy\n");
    return 2;
}

int main(int argc, char **argv)
{
    int points = 60, samples = 1 << 18, threads = 2, perturbed = 6, train = 0, train_perturbed = 1, objective_kind = MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT;
    const char *kt = NULL, *out = NULL, *table_path = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--points") && i + 1 < argc)
            points = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--samples") && i + 1 < argc)
            samples = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc)
            threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--perturbed") && i + 1 < argc)
            perturbed = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--train") && i + 1 < argc)
            train = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--train-perturbed") && i + 1 < argc)
            train_perturbed = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--table") && i + 1 < argc)
            table_path = argv[++i];
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--objective") && i + 1 < argc) {
            ++i;
            if (!strcmp(argv[i], "abs"))
                objective_kind = MF_LTCFIT_ANISO_OBJECTIVE_DEFAULT;
            else if (!strcmp(argv[i], "relative"))
                objective_kind = MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE;
            else {
                fprintf(stderr, "study_aniso_oracle: --objective %s: expected abs or relative\n", argv[i]);
                return 2;
            }
        } else if (argv[i][0] == '-')
            return usage();
        else
            kt = argv[i];
    }
    if (points < 1 || samples < 64 || threads < 1 || threads > 64 || perturbed < 0 || train_perturbed < 0 ||
        START_FIXED + 3 * perturbed >= MAX_STARTS || START_FIXED + 3 * train_perturbed >= MAX_STARTS || train < 0 ||
        train > MAXQ) {
        fprintf(stderr, "study_aniso_oracle: --points >= 1, --samples >= 64, --threads 1..64, --perturbed and "
                        "--train-perturbed 0..%d, --train 0..%d\n",
                (MAX_STARTS - START_FIXED) / 3 - 1, MAXQ);
        return 2;
    }
    float *pub = kt ? abench_read_kt(kt) : NULL;
    if (!pub) {
        fprintf(stderr, "study_aniso_oracle: %s: not an (8, 8, 8, 8, 3, 3) float32 .npy\n", kt ? kt : "(none)");
        return 2;
    }
    double w0 = now(), c0 = cpu_now();
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    mf_ltcfit_aniso_options o;
    mf_ltcfit_aniso_options_default(&o);
    o.threads = threads;
    o.objective = objective_kind;
    mf_table t;
    mf_ltcfit_aniso_result fr;
    int fitted = abench_table_get("study_aniso_oracle", table_path, &o, &t, &fr);
    if (fitted < 0)
        return 1;
    if (fitted) {
        printf("mfkit 8^4 table fitted (objective %s): %.1f s wall; worst residual %.4g, not converged %d\n",
               objective_kind == MF_LTCFIT_ANISO_OBJECTIVE_RELATIVE ? "relative" : "default", now() - w0,
               fr.worst_residual, fr.not_converged);
        mf_ltcfit_aniso_result_free(&fr);
    }

    job j = {ggx, &t, pub, &o, samples, perturbed, points, train, train_perturbed,
             calloc((size_t)points, sizeof(point_result)), 0, PTHREAD_MUTEX_INITIALIZER};
    abench_points pts;
    abench_points_init(&pts);
    for (int i = 0; i < points; ++i)
        abench_next_point(&pts, j.res[i].c.p);
    mf_ltcfit_aniso_options o1 = o;
    o1.threads = 1;
    j.o = &o1;
    pthread_t th[64];
    for (int k = 0; k < threads; ++k)
        pthread_create(&th[k], NULL, worker, &j);
    for (int k = 0; k < threads; ++k)
        pthread_join(th[k], NULL);

    pooled pm = {0}, pp = {0}, pf = {0}, pa = {0}, pb = {0}, pta = {0}, ptb = {0}, ptm = {0}, ptp = {0};
    double se_abs = 0.0, se_rel = 0.0, tr[8] = {0};
    int used = 0, ntrained = 0, agree[4] = {0}, fixed_agree[4] = {0};
    long evals = 0;
    for (int i = 0; i < points; ++i) {
        point_result *r = &j.res[i];
        if (!r->ok)
            continue;
        ++used;
        pool(&pm, r->ea_mfkit, r->er_mfkit);
        pool(&pp, r->ea_pub, r->er_pub);
        pool(&pf, r->ea_fit, r->er_fit);
        pool(&pa, r->ea_oa, r->er_oa);
        pool(&pb, r->ea_ob, r->er_ob);
        for (int k = 0; k < ABENCH_Q; ++k) {
            se_abs += r->c.se[k];
            se_rel += r->c.se[k] / fmax(r->c.mc[k], 0.01 * r->c.albedo);
        }
        const oracle *ors[4] = {&r->oa, &r->ob, &r->tra, &r->trb};
        for (int q = 0; q < (r->ntrain ? 4 : 2); ++q) {
            agree[q] += ors[q]->agree >= 2;
            fixed_agree[q] += ors[q]->agree_fixed >= 2;
        }
        if (r->ntrain) {
            ++ntrained;
            pool(&pta, r->ea_ta, r->er_ta);
            pool(&ptb, r->ea_tb, r->er_tb);
            pool(&ptm, r->ea_mfkit, r->er_mfkit);
            pool(&ptp, r->ea_pub, r->er_pub);
            /* in-sample on the training quads: oracle (a) abs, oracle (b) rel, mfkit, published, MC */
            tr[0] += r->tra.best, tr[1] += r->trb.best, tr[2] += r->train_mfkit_abs, tr[3] += r->train_mfkit_rel;
            tr[4] += r->train_pub_abs, tr[5] += r->train_pub_rel, tr[6] += r->train_se_abs, tr[7] += r->train_se_rel;
        }
        evals += r->evals;
    }
    if (!used) {
        fprintf(stderr, "study_aniso_oracle: no point could be evaluated\n");
        return 1;
    }
    int nq = used * ABENCH_Q;
    se_abs /= nq, se_rel /= nq;
    printf("%d of %d points x %d quads (the cases of bench_ltc_aniso --points %d), Monte Carlo %d samples: mean "
           "standard error %.3g abs, %.3g rel\n",
           used, points, ABENCH_Q, points, samples, se_abs, se_rel);
    printf("On the benchmark's quads (the oracles IN-SAMPLE: fitted to these very quads):\n");
    row("mfkit 8^4 table (interpolated)", &pm, &pp);
    row("published 8^4 table (interpolated)", &pp, &pp);
    row("mfkit fit at the point", &pf, &pp);
    row("oracle (a): min mean abs per point", &pa, &pp);
    row("oracle (b): min mean rel per point", &pb, &pp);
    double oa = pa.sa / pa.n, ob = pb.sr / pb.n, pa_ = pp.sa / pp.n, pr_ = pp.sr / pp.n;
    printf("  MC-corrected bounds (oracle - mean standard error) / (published + mean standard error):\n"
           "  abs: %.6f / %.6f = %.3fx   rel: %.5f / %.5f = %.3fx\n",
           oa - se_abs, pa_ + se_abs, (oa - se_abs) / (pa_ + se_abs), ob - se_rel, pr_ + se_rel,
           (ob - se_rel) / (pr_ + se_rel));
    printf("  starts: %d unperturbed + %d perturbed (+1 cross); points where >= 2 starts reach the best within 1%%: "
           "(a) %d, (b) %d of %d; >= 2 of the 4 unperturbed: (a) %d, (b) %d\n",
           START_FIXED, 3 * perturbed, agree[0], agree[1], used, fixed_agree[0], fixed_agree[1]);
    printf("  target 0.5x published: abs %.6f, rel %.5f -> in-sample oracle (a) abs %s, oracle (b) rel %s\n", 0.5 * pa_,
           0.5 * pr_, oa <= 0.5 * pa_ ? "below" : "ABOVE (unreachable by any single LTC)",
           ob <= 0.5 * pr_ ? "below" : "ABOVE (unreachable by any single LTC)");
    if (ntrained) {
        printf("Fitted to %d OTHER quads per point of the same distribution (%d points; starts: %d unperturbed + %d "
               "perturbed):\n",
               train, ntrained, START_FIXED, 3 * train_perturbed);
        printf("  in-sample on those quads: mfkit abs %.6f rel %.5f; published abs %.6f rel %.5f; oracle (a) abs %.6f "
               "(%.3fx published), oracle (b) rel %.5f (%.3fx published); MC standard error %.3g abs, %.3g rel\n",
               tr[2] / ntrained, tr[3] / ntrained, tr[4] / ntrained, tr[5] / ntrained, tr[0] / ntrained,
               tr[0] / tr[4], tr[1] / ntrained, tr[1] / tr[5], tr[6] / ntrained, tr[7] / ntrained);
        printf("  out of sample, on the benchmark's quads (same %d points):\n", ntrained);
        row("  mfkit 8^4 table", &ptm, &ptp);
        row("  published 8^4 table", &ptp, &ptp);
        row("  oracle (a) trained, tested", &pta, &ptp);
        row("  oracle (b) trained, tested", &ptb, &ptp);
        printf("  points where >= 2 starts reach the best within 1%%: (a) %d, (b) %d of %d; >= 2 of the 4 unperturbed: "
               "(a) %d, (b) %d\n",
               agree[2], agree[3], ntrained, fixed_agree[2], fixed_agree[3]);
    }
    printf("%ld objective evaluations; time: %.1f s wall, %.1f s CPU (whole run)\n", evals, now() - w0,
           cpu_now() - c0);

    if (out) {
        char tmp[4096];
        snprintf(tmp, sizeof tmp, "%s.tmp", out);
        FILE *f = fopen(tmp, "w");
        if (!f) {
            fprintf(stderr, "study_aniso_oracle: %s: cannot write\n", out);
            return 1;
        }
        study_write_header(f, "study_aniso_oracle", argc, argv, "12");
        fprintf(f, "point,alpha_x,alpha_y,theta,phi,albedo,mc_se_abs,mc_se_rel,mfkit_abs,mfkit_rel,published_abs,"
                   "published_rel,fit_abs,fit_rel,oracle_a_abs,oracle_a_rel,oracle_b_abs,oracle_b_rel,starts,"
                   "agree_a,agree_b,train,train_oracle_a_abs_in,train_oracle_b_rel_in,train_mfkit_abs_in,"
                   "train_mfkit_rel_in,train_published_abs_in,train_published_rel_in,trained_a_abs,trained_a_rel,"
                   "trained_b_abs,trained_b_rel\n");
        for (int i = 0; i < points; ++i) {
            point_result *r = &j.res[i];
            if (!r->ok)
                continue;
            double sa = 0.0, sr = 0.0;
            for (int k = 0; k < ABENCH_Q; ++k)
                sa += r->c.se[k], sr += r->c.se[k] / fmax(r->c.mc[k], 0.01 * r->c.albedo);
            fprintf(f, "%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%d",
                    i, r->c.p[0], r->c.p[1], r->c.p[2], r->c.p[3], r->c.albedo, sa / ABENCH_Q, sr / ABENCH_Q,
                    mean_q(r->ea_mfkit), mean_q(r->er_mfkit), mean_q(r->ea_pub), mean_q(r->er_pub), mean_q(r->ea_fit),
                    mean_q(r->er_fit), mean_q(r->ea_oa), mean_q(r->er_oa), mean_q(r->ea_ob), mean_q(r->er_ob),
                    r->oa.starts, r->oa.agree, r->ob.agree);
            if (r->ntrain)
                fprintf(f, ",%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", r->ntrain, r->tra.best,
                        r->trb.best, r->train_mfkit_abs, r->train_mfkit_rel, r->train_pub_abs, r->train_pub_rel,
                        mean_q(r->ea_ta), mean_q(r->er_ta), mean_q(r->ea_tb), mean_q(r->er_tb));
            else
                fprintf(f, ",0,nan,nan,nan,nan,nan,nan,nan,nan,nan,nan\n");
        }
        if (fclose(f) != 0 || rename(tmp, out) != 0) {
            remove(tmp);
            fprintf(stderr, "study_aniso_oracle: %s: cannot write\n", out);
            return 1;
        }
    }
    mf_table_free(&t);
    free(j.res);
    free(pub);
    return 0;
}
