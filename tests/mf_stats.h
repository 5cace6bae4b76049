/*
 * mf_stats.h -- statistics helpers shared by the chi-square tests (tests/ only).
 */
#ifndef MF_STATS_H
#define MF_STATS_H

#include <math.h>
#include <stdlib.h>

/* ---- regularized upper incomplete gamma Q(a, x) ----------------------------------------------
 * Numerical Recipes in C, 2nd ed. (Press et al. 1992), Sec. 6.2: gammq() with the series gser()
 * for x < a + 1 and the continued fraction gcf() (modified Lentz) otherwise.  ITMAX is raised
 * from NR's 100 to 10000: the series needs O(sqrt(a)) terms and a = dof / 2 is up to ~400 here. */
#define IG_ITMAX 10000
#define IG_EPS 1e-15
#define IG_FPMIN 1e-300

static inline double gamma_p_series(double a, double x)
{
    double ap = a, sum = 1.0 / a, del = sum;
    for (int n = 0; n < IG_ITMAX; ++n) {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if (fabs(del) < fabs(sum) * IG_EPS)
            break;
    }
    return sum * exp(-x + a * log(x) - lgamma(a));
}

static inline double gamma_q_cf(double a, double x)
{
    double b = x + 1.0 - a, c = 1.0 / IG_FPMIN, d = 1.0 / b, h = d;
    for (int i = 1; i <= IG_ITMAX; ++i) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < IG_FPMIN)
            d = IG_FPMIN;
        c = b + an / c;
        if (fabs(c) < IG_FPMIN)
            c = IG_FPMIN;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < IG_EPS)
            break;
    }
    return exp(-x + a * log(x) - lgamma(a)) * h;
}

static inline double gamma_q(double a, double x)
{
    if (!(a > 0.0) || !(x >= 0.0))
        return NAN;
    if (x == 0.0)
        return 1.0;
    if (x < a + 1.0)
        return 1.0 - gamma_p_series(a, x);
    return gamma_q_cf(a, x);
}

/* p-value of a chi-square statistic with dof degrees of freedom. */
static inline double chi2_pvalue(double chi2, int dof) { return gamma_q(0.5 * dof, 0.5 * chi2); }

/* ---- pooled chi-square statistic ---------------------------------------------------------------
 * As pbrt-v3's chi2test() and Mitsuba 3's chi2: the n cells are sorted by expected count; cells of
 * expected count 0 are left out (their observations counted in *zero_hits, to be judged by the
 * caller), cells below min_expected are pooled, in order, with the following ones while the pool
 * stays below min_expected, and the pool counts as one cell.  dof = cells used - 1 (all
 * parameters known: only the total is constrained).  order: scratch space of n ints. */
typedef struct chi2_pooled {
    double chi2;
    int dof;
    int pooled_cells;
    long zero_hits;
} chi2_pooled;

static const double *chi2_sort_key; /* for qsort */
static inline int chi2_cmp_expected(const void *a, const void *b)
{
    double x = chi2_sort_key[*(const int *)a], y = chi2_sort_key[*(const int *)b];
    return (x > y) - (x < y);
}

static inline chi2_pooled chi2_pool(const double *expected, const long *observed, int *order, int n,
                                    double min_expected)
{
    chi2_pooled r = {0.0, 0, 0, 0};
    for (int c = 0; c < n; ++c)
        order[c] = c;
    chi2_sort_key = expected;
    qsort(order, (size_t)n, sizeof order[0], chi2_cmp_expected);
    double pooled_obs = 0.0, pooled_exp = 0.0;
    for (int k = 0; k < n; ++k) {
        int c = order[k];
        if (expected[c] == 0.0) {
            r.zero_hits += observed[c];
        } else if (expected[c] < min_expected || (pooled_exp > 0.0 && pooled_exp < min_expected)) {
            pooled_obs += observed[c];
            pooled_exp += expected[c];
            r.pooled_cells++;
        } else {
            double diff = observed[c] - expected[c];
            r.chi2 += diff * diff / expected[c];
            r.dof++;
        }
    }
    if (pooled_exp > 0.0) {
        double diff = pooled_obs - pooled_exp;
        r.chi2 += diff * diff / pooled_exp;
        r.dof++;
    }
    r.dof -= 1;
    return r;
}

#define CHI2_TWO_PI 6.28318530717958647692528676655900577 /* 2 pi: the same double as 2.0 * MF_PI */

/* The azimuth cell (of n_phi equal cells over [0, 2 pi)) of the direction (x, y). */
static inline int chi2_phi_cell(double y, double x, int n_phi)
{
    double phi = atan2(y, x);
    if (phi < 0.0)
        phi += CHI2_TWO_PI;
    int j = (int)(phi * (n_phi / CHI2_TWO_PI));
    return j >= n_phi ? n_phi - 1 : (j < 0 ? 0 : j);
}

#endif /* MF_STATS_H */
