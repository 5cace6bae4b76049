/*
 * mf_stats.h -- statistics helpers shared by the chi-square tests (tests/ only).
 */
#ifndef MF_STATS_H
#define MF_STATS_H

#include <math.h>

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

#endif /* MF_STATS_H */
