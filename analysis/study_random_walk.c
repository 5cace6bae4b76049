/*
 * study_random_walk.c -- mfkit's energy compensation against true multiple scattering: the random walk
 * on the Smith microsurface (mf_walk.h) [Heitz, Hanika, d'Eon and Dachsbacher 2016], GGX and Beckmann
 * (issue 14).
 *
 *   build-dir/analysis/study_random_walk [--walks N] [--split-walks N] [--seed S] [--ndf ggx|beckmann|ggx,beckmann]
 *                                        [--alphas LIST] [--mus LIST] [--etas LIST] [--out FILE]
 *
 * Every row starts with its NDF (ndf: ggx or beckmann; default both, GGX first, so GGX's numbers do not
 * depend on whether Beckmann follows).
 *
 * Dielectric (rows case=dielectric), for every alpha, eta of --etas and 1/eta, and view mu of --mus
 * plus the cosine average (avg = 1, mu = nan: views drawn with density 2 mu):
 *   the walk           N walks from the view: R_walk, T_walk (all orders; R + T = 1, every walk ends),
 *                      R1_walk, T1_walk (the walks that leave after one bounce), t_walk = the fraction of
 *                      the walk's multiple scattering (>= 2 bounces) that is transmitted, with binomial
 *                      standard errors (_se);
 *   the walk's single  T1_beta: its single-scattering transmission by quadrature (mf_walk_single, the
 *   scattering         Beta-function G2), T1_beta_err its estimate;
 *   mfkit              E_r, E_t (mf_albedo_dielectric, joint G2: the transmission's is pbrt-v4's and
 *                      Cycles' 1 / (1 + Lambda_o + Lambda_t)), E_avg of this side and the other
 *                      (mf_energy_dielectric_eavg), F_avg of both (mf_energy_favg_dielectric), the split
 *                      t (mf_energy_dielectric_ms_split), and the compensated albedos
 *                      R_kc = E_r + (1 - t)(1 - E), T_kc = E_t + t (1 - E), E = E_r + E_t;
 *   errors             err_T = T_kc - T_walk (= R_walk - R_kc: both sum to 1), err_T_z = err_T / T_walk_se;
 *                      its parts: dT_single = E_t - T1_beta (the transmission G2, deterministic) and
 *                      dT_ms = t (1 - E) - (T_walk - T1_walk) (the compensation's transmitted energy
 *                      against the walk's); dt = t - t_walk (the split itself, on the walk's own
 *                      multiple scattering), dt_z = dt / t_walk_se.
 *   the walk closure   t_clos: mfkit's split closed by the walk (mf_energy_dielectric_walk_split, --split-walks
 *                      walks per side from its own stream, seed 14: the table's estimator, not this study's
 *                      walks), the same on all rows of an (alpha, eta); T_clos = E_t + t_clos (1 - E),
 *                      err_T_clos = T_clos - T_walk, err_T_clos_z = err_T_clos / T_walk_se.
 *   In the avg rows E_r, E_t are cosine averages by Gauss-Legendre in mu (12 points per panel, panels
 *   ending at the kinks of E(mu) for eta < 1, as in mf_energy_dielectric_eavg), E = E_avg.
 * Conductor (case=conductor), for every alpha and mu (and avg), channel F: none (F = 1) and the three
 * channels of a gold-like exact conductor (eta, k) = (0.143, 3.983), (0.374, 2.385), (1.442, 1.603):
 *   R_walk the walk's albedo (its mean weight, the product of F over the bounces), R1_walk its first
 *   bounce; E_r the single-scattering albedo with that F (mf_albedo_microfacet), E_avg (F = 1), F_avg
 *   (mf_energy_favg_conductor); R_kc = E_F + (1 - E) F_avg^2 E_avg / (1 - F_avg (1 - E_avg)) [Kulla and
 *   Conty 2017, the Fresnel of the compensation lobe]; err_R = R_kc - R_walk, err_R_z.
 * Every cell has its own generator stream (seed S, stream = the cell's index), so the output does not
 * depend on the order; stdout gets a summary and the CPU time of each part.
 * Output: FILE (default notebooks_data/random_walk.csv), its first line the provenance header
 * (analysis/study_header.h), written atomically.  Exit 2 on a bad argument, 3 if FILE cannot be written.
 */
#include "mfkit/io/mf_io.h"
#include "mfkit/mfkit.h"
#include "study_header.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAXLIST 32
#define MAX_BOUNCES 100000

static double cpu_now(void) { return (double)clock() / CLOCKS_PER_SEC; }

static int parse_list(const char *s, double *v, int cap, double lo, double hi)
{
    int n = 0;
    const char *p = s;
    while (*p) {
        char *end;
        double x = strtod(p, &end);
        if (end == p || !(x >= lo && x <= hi) || n == cap)
            return -1;
        v[n++] = x;
        p = end;
        if (*p == ',')
            ++p;
        else if (*p)
            return -1;
    }
    return n;
}

typedef struct walk_stats {
    long n, up, down, up1, down1, ms, ms_down, stopped;
} walk_stats;

static double se_p(long k, long n)
{
    if (n <= 0)
        return NAN;
    double p = (double)k / n;
    return sqrt(p * (1.0 - p) / n);
}

/* mu of the view: the given one, or (mu < 0) drawn with density 2 mu */
static mf_vec3 view_dir(double mu, mf_pcg32 *rng)
{
    if (mu < 0.0)
        mu = sqrt(1.0 - mf_pcg32_next_double(rng));
    return mf_vec3_make(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
}

static int walk_dielectric_cell(mf_ndf ndf, double eta, double mu, long n, mf_pcg32 *rng, walk_stats *s)
{
    memset(s, 0, sizeof *s);
    for (long i = 0; i < n; ++i) {
        mf_walk_path p;
        mf_vec3 wo = view_dir(mu, rng);
        if (mf_walk_dielectric(ndf, eta, wo, MAX_BOUNCES, rng, &p) != MF_OK)
            return -1;
        ++s->n;
        if (p.side == 0) {
            ++s->stopped;
            continue;
        }
        if (p.side > 0) {
            ++s->up;
            s->up1 += p.bounces == 1;
        } else {
            ++s->down;
            s->down1 += p.bounces == 1;
        }
        if (p.bounces >= 2) {
            ++s->ms;
            s->ms_down += p.side < 0;
        }
    }
    return 0;
}

/* kinks of E(mu) for eta < 1 (mf_energy.h, mf_energy_dielectric_eavg): panel ends in (0, 1) */
static int panels(double eta, double *bp)
{
    int n = 0;
    bp[n++] = 0.0;
    if (eta < 1.0) {
        double k[3] = {eta, sqrt(1.0 - eta * eta), 2.0 * eta * sqrt(1.0 - eta * eta)};
        for (int i = 0; i < 3; ++i)
            if (k[i] > 1e-6 && k[i] < 1.0 - 1e-6)
                bp[n++] = k[i];
        for (int i = 1; i < n; ++i) /* sort */
            for (int j = i; j > 1 && bp[j] < bp[j - 1]; --j) {
                double t = bp[j];
                bp[j] = bp[j - 1];
                bp[j - 1] = t;
            }
    }
    bp[n++] = 1.0;
    return n;
}

/* 2 integral E_r(mu) mu dmu and the same of E_t, Gauss-Legendre per panel (ng points) */
static int diel_avgs(mf_ndf ndf, double eta, int ng, double *er, double *et)
{
    double x[16], w[16], bp[5];
    if (mf_quad_gauss_legendre(ng, x, w) != MF_OK)
        return -1;
    int nb = panels(eta, bp);
    *er = *et = 0.0;
    for (int p = 0; p + 1 < nb; ++p)
        for (int i = 0; i < ng; ++i) {
            double a = bp[p], b = bp[p + 1], mu = 0.5 * (a + b) + 0.5 * (b - a) * x[i];
            mf_result r, t;
            if (mf_albedo_dielectric(ndf, MF_G2_JOINT, mu, eta, &r, &t) != MF_OK)
                return -1;
            double wt = 0.5 * (b - a) * w[i] * 2.0 * mu;
            *er += wt * r.val;
            *et += wt * t.val;
        }
    return 0;
}

static int conductor_avg_ef(mf_ndf ndf, mf_fresnel f, int ng, double *ef)
{
    /* 2 integral E_F(mu) mu dmu on the panels [0, 1/2], [1/2, 1] in s = sqrt(mu) (as mf_energy_eavg) */
    double x[16], w[16];
    if (mf_quad_gauss_legendre(ng, x, w) != MF_OK)
        return -1;
    *ef = 0.0;
    for (int p = 0; p < 2; ++p)
        for (int j = 0; j < ng; ++j) {
            double s = 0.25 * (2 * p + 1 + x[j]), wt = 0.25 * w[j] * 4.0 * s * s * s;
            mf_microfacet m = {ndf, MF_G2_JOINT, f};
            mf_result e;
            if (mf_albedo_microfacet(&m, mf_vec3_make(sqrt(1.0 - s * s * s * s), 0.0, s * s), &e) != MF_OK)
                return -1;
            *ef += wt * e.val;
        }
    return 0;
}

static void usage(FILE *f)
{
    fprintf(f, "usage: study_random_walk [--walks N] [--split-walks N] [--seed S] [--ndf ggx|beckmann|ggx,beckmann] [--alphas LIST]\n"
               "                         [--mus LIST] [--etas LIST] [--out FILE]\n"
               "  mfkit's dielectric and conductor energy compensation against the random walk on the Smith\n"
               "  microsurface (default both NDFs); LIST is comma-separated: alphas in [0.01, 1], mus in (0, 1], etas in\n"
               "  (1, 3] (each with its inverse); --split-walks: walks per side of the walk closure (default 262144, the\n"
               "  table's).  Defaults: --walks 100000 --seed 1 --alphas 0.1,0.2,0.3,0.5,0.7,1\n"
               "  --mus 0.1,0.3,0.5,0.7,0.9 --etas 1.1,1.33,1.5,2 --out notebooks_data/random_walk.csv\n");
}

int main(int argc, char **argv)
{
    long walks = 100000, split_walks = MF_ENERGY_WALK_SPLIT_WALKS;
    mf_ndf_type ndf_types[2] = {MF_NDF_GGX, MF_NDF_BECKMANN};
    int n_ndf = 2;
    unsigned long long seed = 1;
    double alphas[MAXLIST] = {0.1, 0.2, 0.3, 0.5, 0.7, 1.0}, mus[MAXLIST] = {0.1, 0.3, 0.5, 0.7, 0.9},
           etas_in[MAXLIST] = {1.1, 1.33, 1.5, 2.0};
    int na = 6, nm = 5, ne = 4;
    const char *out_path = "notebooks_data/random_walk.csv";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            usage(stdout);
            return 0;
        }
        if (i + 1 >= argc) {
            fprintf(stderr, "study_random_walk: %s: missing value (or unknown option)\n", a);
            return 2;
        }
        const char *v = argv[++i];
        char *end;
        if (!strcmp(a, "--walks")) {
            walks = strtol(v, &end, 10);
            if (*end || walks < 100 || walks > 1000000000L) {
                fprintf(stderr, "study_random_walk: --walks %s: expected an integer in [100, 1e9]\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--split-walks")) {
            split_walks = strtol(v, &end, 10);
            if (*end || split_walks < 1000 || split_walks > 1000000000L) {
                fprintf(stderr, "study_random_walk: --split-walks %s: expected an integer in [1000, 1e9]\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--seed")) {
            seed = strtoull(v, &end, 10);
            if (*end || !*v) {
                fprintf(stderr, "study_random_walk: --seed %s: expected a non-negative integer\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--alphas")) {
            if ((na = parse_list(v, alphas, MAXLIST, 0.01, 1.0)) < 1) {
                fprintf(stderr, "study_random_walk: --alphas %s: expected a comma-separated list in [0.01, 1]\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--mus")) {
            if ((nm = parse_list(v, mus, MAXLIST, 1e-3, 1.0)) < 1) {
                fprintf(stderr, "study_random_walk: --mus %s: expected a comma-separated list in [0.001, 1]\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--etas")) {
            if ((ne = parse_list(v, etas_in, MAXLIST / 2, 1.001, 3.0)) < 1) {
                fprintf(stderr, "study_random_walk: --etas %s: expected a comma-separated list in [1.001, 3]\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--ndf")) {
            if (!strcmp(v, "ggx") || !strcmp(v, "beckmann")) {
                n_ndf = 1;
                ndf_types[0] = !strcmp(v, "ggx") ? MF_NDF_GGX : MF_NDF_BECKMANN;
            } else if (!strcmp(v, "ggx,beckmann")) {
                n_ndf = 2;
            } else {
                fprintf(stderr, "study_random_walk: --ndf %s: expected ggx, beckmann or ggx,beckmann\n", v);
                return 2;
            }
        } else if (!strcmp(a, "--out")) {
            out_path = v;
        } else {
            fprintf(stderr, "study_random_walk: %s: unknown option (see --help)\n", a);
            return 2;
        }
    }

    mf_io_atomic out;
    char io_msg[1024];
    if (mf_io_atomic_begin(&out, out_path, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_random_walk: %s\n", io_msg);
        return 3;
    }
    FILE *f = out.file;
    char seed_s[32];
    snprintf(seed_s, sizeof seed_s, "%llu", seed);
    study_write_header(f, "study_random_walk", argc, argv, seed_s);
    fprintf(f, "ndf,case,channel,alpha,eta,mu,avg,walks,R_walk,R_walk_se,T_walk,T_walk_se,R1_walk,T1_walk,T1_beta,"
               "T1_beta_err,E_r,E_t,E_avg,E_avg_inv,F_avg,F_avg_inv,t_split,R_kc,T_kc,err_R,err_T,err_T_z,dT_single,"
               "dT_ms,t_walk,t_walk_se,dt,dt_z,t_clos,T_clos,err_T_clos,err_T_clos_z\n");

    double t_walk = 0.0, t_mfkit = 0.0, t_single = 0.0, t_closure = 0.0, wall0 = (double)time(NULL);
    double cpu0 = cpu_now();
    unsigned long long stream = 0;
    int status = 0;
    double worst_z = 0.0, worst_dt = 0.0, worst_err = 0.0;
    char worst_z_at[128] = "", worst_dt_at[128] = "", worst_err_at[128] = "";
    long total_stopped = 0;
    /* per (alpha, eta side): the cosine averages of mfkit's split and the walk's (for the summary) */
    static double sum_tc[MAXLIST][MAXLIST], worst_clos[MAXLIST], worst_clos_z[MAXLIST], worst_kc[MAXLIST];
    static double sum_t[MAXLIST][MAXLIST], sum_tw[MAXLIST][MAXLIST], sum_tw_se[MAXLIST][MAXLIST],
        sum_ew[MAXLIST][MAXLIST], sum_favg[MAXLIST][MAXLIST];

    for (int nd = 0; nd < n_ndf && !status; ++nd) {
    const mf_ndf_type type = ndf_types[nd];
    const char *ndf_name = mf_ndf_type_name(type);
    worst_z = worst_dt = worst_err = 0.0;
    worst_z_at[0] = worst_dt_at[0] = worst_err_at[0] = '\0';
    for (int a = 0; a < na; ++a)
        worst_clos[a] = worst_clos_z[a] = worst_kc[a] = 0.0;
    /* ---- dielectric ---- */
    printf("== %s\ndielectric: T_kc - T_walk and t - t_walk (z = in walk standard errors)\n", ndf_name);
    printf("%6s %7s %6s %9s %9s %7s %9s %9s %9s %7s\n", "alpha", "eta", "mu", "T_walk", "err_T", "z", "dT_single",
           "t", "t_walk", "dt_z");
    for (int a = 0; a < na && !status; ++a)
        for (int e = 0; e < 2 * ne && !status; ++e) {
            double eta = e < ne ? etas_in[e] : 1.0 / etas_in[e - ne];
            mf_ndf ndf = mf_ndf_make(type, alphas[a], alphas[a]);
            double c0 = cpu_now();
            mf_result eavg, eavg_inv, favg, favg_inv;
            double t = NAN;
            if (mf_energy_dielectric_eavg(type, MF_G2_JOINT, alphas[a], eta, &eavg) != MF_OK
                || mf_energy_dielectric_eavg(type, MF_G2_JOINT, alphas[a], 1.0 / eta, &eavg_inv) != MF_OK
                || mf_energy_favg_dielectric(eta, &favg) != MF_OK || mf_energy_favg_dielectric(1.0 / eta, &favg_inv) != MF_OK
                || mf_energy_dielectric_ms_split(eta, eavg.val, eavg_inv.val, favg.val, favg_inv.val, &t) != MF_OK) {
                fprintf(stderr, "study_random_walk: mfkit's energy terms failed at alpha %g, eta %g\n", alphas[a], eta);
                status = 1;
                break;
            }
            t_mfkit += cpu_now() - c0;
            c0 = cpu_now();
            /* the closure by the walk: its own walks (stream 2 x cell index, seed 14), independent of the study's */
            mf_energy_walk_split ws;
            if (mf_energy_dielectric_walk_split(type, alphas[a], eta, eavg.val, eavg_inv.val, favg.val, favg_inv.val,
                                                split_walks, MF_ENERGY_WALK_SPLIT_SEED,
                                                2u * (uint64_t)(((nd * MAXLIST) + a) * MAXLIST + e), &ws) != MF_OK) {
                fprintf(stderr, "study_random_walk: the walk closure failed at alpha %g, eta %g\n", alphas[a], eta);
                status = 1;
                break;
            }
            double t_clos = ws.t[0];
            t_closure += cpu_now() - c0;
            for (int m = 0; m <= nm && !status; ++m) {
                int avg = m == nm;
                double mu = avg ? -1.0 : mus[m];
                double er, et, t1b = NAN, t1b_err = NAN;
                c0 = cpu_now();
                if (avg) {
                    if (diel_avgs(ndf, eta, 12, &er, &et) != 0)
                        status = 1;
                } else {
                    mf_result r, tr;
                    if (mf_albedo_dielectric(ndf, MF_G2_JOINT, mu, eta, &r, &tr) != MF_OK)
                        status = 1;
                    er = r.val;
                    et = tr.val;
                }
                t_mfkit += cpu_now() - c0;
                c0 = cpu_now();
                if (!avg) {
                    mf_result r1, t1;
                    if (mf_walk_single(ndf, mu, eta, 16, &r1, &t1) != MF_OK)
                        status = 1;
                    t1b = t1.val;
                    t1b_err = t1.err;
                }
                t_single += cpu_now() - c0;
                if (status) {
                    fprintf(stderr, "study_random_walk: quadrature failed at alpha %g, eta %g, mu %g\n", alphas[a], eta, mu);
                    break;
                }
                c0 = cpu_now();
                mf_pcg32 rng;
                mf_pcg32_seed(&rng, seed, stream++);
                walk_stats s;
                if (walk_dielectric_cell(ndf, eta, mu, walks, &rng, &s) != 0) {
                    fprintf(stderr, "study_random_walk: walk failed at alpha %g, eta %g\n", alphas[a], eta);
                    status = 1;
                    break;
                }
                t_walk += cpu_now() - c0;
                total_stopped += s.stopped;
                double n = (double)s.n;
                double E = avg ? eavg.val : er + et;
                double R_w = s.up / n, T_w = s.down / n, se = se_p(s.down, s.n);
                double R_kc = er + (1.0 - t) * (1.0 - E), T_kc = et + t * fmax(0.0, 1.0 - E);
                double err_T = T_kc - T_w, z = err_T / se;
                double tw = s.ms ? (double)s.ms_down / s.ms : NAN, tw_se = se_p(s.ms_down, s.ms);
                double dt = t - tw, dtz = dt / tw_se;
                double dT_single = avg ? NAN : et - t1b;
                double dT_ms = t * (1.0 - E) - (s.down - s.down1) / n;
                double T_clos = et + t_clos * fmax(0.0, 1.0 - E), err_c = T_clos - T_w;
                fprintf(f,
                        "%s,dielectric,none,%.17g,%.17g,%.17g,%d,%ld,%.10g,%.4g,%.10g,%.4g,%.10g,%.10g,%.10g,%.4g,%.12g,%.12g,"
                        "%.12g,%.12g,%.12g,%.12g,%.12g,%.10g,%.10g,%.6g,%.6g,%.4g,%.6g,%.6g,%.10g,%.4g,%.6g,%.4g,%.10g,%.10g,%.6g,%.4g\n",
                        ndf_name, alphas[a], eta, avg ? NAN : mu, avg, s.n, R_w, se, T_w, se, s.up1 / n, s.down1 / n, t1b, t1b_err,
                        er, et, eavg.val, eavg_inv.val, favg.val, favg_inv.val, t, R_kc, T_kc, R_kc - R_w, err_T, z,
                        dT_single, dT_ms, tw, tw_se, dt, dtz, t_clos, T_clos, err_c, err_c / se);
                if (avg || m == 0 || m == nm - 1)
                    printf("%6.2f %7.4f %6s %9.5f %+9.5f %+7.1f %+9.5f %9.4f %9.4f %+7.1f\n", alphas[a], eta,
                           avg ? "avg" : (m == 0 ? "min" : "max"), T_w, err_T, z, dT_single, t, tw, dtz);
                if (fabs(z) > fabs(worst_z)) {
                    worst_z = z;
                    snprintf(worst_z_at, sizeof worst_z_at, "alpha %g, eta %.4f, mu %s%.2f (err_T %+.5f)", alphas[a],
                             eta, avg ? "avg " : "", avg ? 0.0 : mu, err_T);
                }
                if (fabs(err_T) > fabs(worst_err)) {
                    worst_err = err_T;
                    snprintf(worst_err_at, sizeof worst_err_at, "alpha %g, eta %.4f, mu %s%.2f (z %+.1f)", alphas[a],
                             eta, avg ? "avg " : "", avg ? 0.0 : mu, z);
                }
                if (avg && fabs(err_c) > fabs(worst_clos[a]))
                    worst_clos[a] = err_c, worst_clos_z[a] = err_c / se;
                if (avg && fabs(err_T) > fabs(worst_kc[a]))
                    worst_kc[a] = err_T;
                if (avg) {
                    sum_t[a][e] = t;
                    sum_tc[a][e] = t_clos;
                    sum_tw[a][e] = tw;
                    sum_tw_se[a][e] = tw_se;
                    sum_ew[a][e] = (s.up1 + s.down1) / n; /* the walk's own single-scattering E_avg */
                    sum_favg[a][e] = favg.val;
                }
                if (avg && s.ms > 1000 && fabs(dt) > fabs(worst_dt)) {
                    worst_dt = dt;
                    snprintf(worst_dt_at, sizeof worst_dt_at, "alpha %g, eta %.4f (t %.4f, t_walk %.4f +- %.4f)",
                             alphas[a], eta, t, tw, tw_se);
                }
            }
        }

    /* the split's formula fed with the walk's own single scattering (E_avg = R1 + T1 of the walk, which has
     * the Beta-function transmission): does the formula, or the E it is given, put the energy on the wrong side? */
    if (!status) {
        printf("split, cosine averages: mfkit's t, the same formula with the walk's own E_avg (t_self), the walk's "
               "t_walk, the walk closure t_clos\n%6s %7s %8s %8s %8s %8s %8s\n", "alpha", "eta", "t", "t_self", "t_walk", "se",
               "t_clos");
        for (int a = 0; a < na; ++a)
            for (int e = 0; e < 2 * ne; ++e) {
                int o = e < ne ? e + ne : e - ne;
                double eta = e < ne ? etas_in[e] : 1.0 / etas_in[e - ne], ts = NAN;
                if (mf_energy_dielectric_ms_split(eta, fmin(1.0, sum_ew[a][e]), fmin(1.0, sum_ew[a][o]), sum_favg[a][e],
                                                  sum_favg[a][o], &ts) != MF_OK)
                    ts = NAN;
                printf("%6.2f %7.4f %8.4f %8.4f %8.4f %8.4f %8.4f\n", alphas[a], eta, sum_t[a][e], ts, sum_tw[a][e],
                       sum_tw_se[a][e], sum_tc[a][e]);
            }
        printf("renderer-visible, cosine averages: worst over the etas of T_kc - T_walk and T_clos - T_walk (z)\n");
        for (int a = 0; a < na; ++a)
            printf("  alpha %.2f: kc %+.4f  closure %+.4f (%+.1f se)\n", alphas[a], worst_kc[a], worst_clos[a],
                   worst_clos_z[a]);
    }

    /* ---- conductor ---- */
    const char *chan[4] = {"none", "gold_r", "gold_g", "gold_b"};
    mf_fresnel fr[4] = {{MF_FRESNEL_NONE, 0.0, 0.0, 0.0},
                        {MF_FRESNEL_CONDUCTOR, 0.0, 0.143, 3.983},
                        {MF_FRESNEL_CONDUCTOR, 0.0, 0.374, 2.385},
                        {MF_FRESNEL_CONDUCTOR, 0.0, 1.442, 1.603}};
    double worst_cz = 0.0;
    char worst_cz_at[128] = "";
    printf("conductor: R_kc - R_walk per channel (F = 1 and gold-like)\n");
    for (int a = 0; a < na && !status; ++a) {
        mf_ndf ndf = mf_ndf_make(type, alphas[a], alphas[a]);
        double c0 = cpu_now();
        mf_result eavg, favg[4];
        if (mf_energy_eavg(type, MF_G2_JOINT, alphas[a], &eavg) != MF_OK)
            status = 1;
        favg[0].val = 1.0;
        for (int c = 1; c < 4 && !status; ++c)
            if (mf_energy_favg_conductor(fr[c].eta, fr[c].k, &favg[c]) != MF_OK)
                status = 1;
        t_mfkit += cpu_now() - c0;
        for (int m = 0; m <= nm && !status; ++m) {
            int avg = m == nm;
            double mu = avg ? -1.0 : mus[m];
            double ef[4], e1 = NAN;
            c0 = cpu_now();
            for (int c = 0; c < 4 && !status; ++c) {
                if (avg) {
                    if (conductor_avg_ef(ndf, fr[c], 12, &ef[c]) != 0)
                        status = 1;
                } else {
                    mf_microfacet mm = {ndf, MF_G2_JOINT, fr[c]};
                    mf_result r;
                    if (mf_albedo_microfacet(&mm, mf_vec3_make(sqrt(1.0 - mu * mu), 0.0, mu), &r) != MF_OK)
                        status = 1;
                    ef[c] = r.val;
                }
            }
            e1 = avg ? eavg.val : ef[0];
            t_mfkit += cpu_now() - c0;
            if (status) {
                fprintf(stderr, "study_random_walk: conductor albedo failed at alpha %g\n", alphas[a]);
                break;
            }
            c0 = cpu_now();
            mf_pcg32 rng;
            mf_pcg32_seed(&rng, seed, stream++);
            double sw[4] = {0}, sq[4] = {0}, s1[4] = {0};
            long stopped = 0;
            for (long i = 0; i < walks; ++i) {
                mf_walk_path p;
                double wgt[4];
                mf_vec3 wo = view_dir(mu, &rng);
                if (mf_walk_conductor(ndf, wo, fr, 4, MAX_BOUNCES, &rng, &p, wgt) != MF_OK) {
                    status = 1;
                    break;
                }
                if (p.side != 1) {
                    ++stopped;
                    continue;
                }
                for (int c = 0; c < 4; ++c) {
                    sw[c] += wgt[c];
                    sq[c] += wgt[c] * wgt[c];
                    if (p.bounces == 1)
                        s1[c] += wgt[c];
                }
            }
            t_walk += cpu_now() - c0;
            total_stopped += stopped;
            if (status) {
                fprintf(stderr, "study_random_walk: conductor walk failed at alpha %g\n", alphas[a]);
                break;
            }
            for (int c = 0; c < 4; ++c) {
                double n = (double)walks, mean = sw[c] / n, se = sqrt(fmax(0.0, sq[c] / n - mean * mean) / n);
                double fa = favg[c].val, ea = eavg.val;
                double fms = fa * fa * ea / (1.0 - fa * (1.0 - ea)); /* [Kulla and Conty 2017] */
                double r_kc = ef[c] + (1.0 - e1) * fms, err = r_kc - mean;
                /* F = 1: the walk's albedo is exactly 1 (se 0); z is left nan there */
                double z = se > 0.0 ? err / se : NAN;
                fprintf(f,
                        "%s,conductor,%s,%.17g,nan,%.17g,%d,%ld,%.10g,%.4g,0,0,%.10g,0,nan,nan,%.12g,0,%.12g,nan,%.12g,nan,nan,"
                        "%.10g,0,%.6g,nan,%.4g,nan,nan,nan,nan,nan,nan,nan,nan,nan,nan\n",
                        ndf_name, chan[c], alphas[a], avg ? NAN : mu, avg, walks, mean, se, s1[c] / n, ef[c], eavg.val, fa, r_kc,
                        err, z);
                if (isfinite(z) && fabs(z) > fabs(worst_cz)) {
                    worst_cz = z;
                    snprintf(worst_cz_at, sizeof worst_cz_at, "alpha %g, mu %s%.2f, %s (R_kc %.5f, R_walk %.5f)",
                             alphas[a], avg ? "avg " : "", avg ? 0.0 : mu, chan[c], r_kc, mean);
                }
                if (m == nm && c > 0)
                    printf("  alpha %.2f avg %s: R_walk %.5f +- %.5f, R_kc %.5f, err %+.5f (%+.1f se)\n", alphas[a],
                           chan[c], mean, se, r_kc, err, z);
            }
        }
    }
    if (!status)
        printf("dielectric: largest |err_T| %.5f at %s\n", worst_err, worst_err_at);
    if (!status)
        printf("dielectric: largest |z| %.1f at %s\n", worst_z, worst_z_at);
    if (!status)
        printf("dielectric: largest |t - t_walk| (cosine averages) %.4f at %s\n", worst_dt, worst_dt_at);
    if (!status)
        printf("conductor: largest |z| %.1f at %s\n", worst_cz, worst_cz_at);
    }
    if (status) {
        mf_io_atomic_abort(&out);
        return 1;
    }
    if (mf_io_atomic_commit(&out, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_random_walk: %s\n", io_msg);
        return 3;
    }
    printf("walks stopped at %d bounces: %ld\n", MAX_BOUNCES, total_stopped);
    printf("CPU: walks %.1f s, mfkit's energy terms %.1f s, single-scattering quadrature %.1f s, walk closure %.1f s; "
           "total %.1f s (wall %.0f s)\n",
           t_walk, t_mfkit, t_single, t_closure, cpu_now() - cpu0, (double)time(NULL) - wall0);
    printf("wrote %s\n", out_path);
    return 0;
}
