/*
 * test_solver.c -- the Ceres bridge (mf_solver.h): known fits with analytic Jacobians, bounds,
 * failing callbacks, invalid arguments, and bitwise determinism.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include <mfkit/fit/mf_solver.h>

#include "mf_test.h"

/* ---- y = a exp(b x) on noise-free data --------------------------------------------------- */

#define EXP_N 20
static const double EXP_A = 2.5, EXP_B = -1.3;

typedef struct exp_data {
    double x[EXP_N], y[EXP_N];
} exp_data;

static void exp_data_init(exp_data *d)
{
    for (int i = 0; i < EXP_N; ++i) {
        d->x[i] = 0.1 * i; /* x in [0, 1.9] */
        d->y[i] = EXP_A * exp(EXP_B * d->x[i]);
    }
}

/* r_i = a exp(b x_i) - y_i;  dr/da = exp(b x_i), dr/db = a x_i exp(b x_i). */
static int exp_residuals(void *user, const double *p, double *r, double *jac)
{
    const exp_data *d = (const exp_data *)user;
    for (int i = 0; i < EXP_N; ++i) {
        double e = exp(p[1] * d->x[i]);
        r[i] = p[0] * e - d->y[i];
        if (jac) {
            jac[2 * i + 0] = e;
            jac[2 * i + 1] = p[0] * d->x[i] * e;
        }
    }
    return 0;
}

/* ---- Rosenbrock as residuals: r = (10 (x1 - x0^2), 1 - x0), minimum 0 at (1, 1) ----------- */

typedef struct rosen_state {
    int calls;
    int out_of_bounds; /* evaluations outside [lower, upper] (if bounded) */
    const double *lower, *upper;
} rosen_state;

static int rosen_residuals(void *user, const double *p, double *r, double *jac)
{
    rosen_state *s = (rosen_state *)user;
    if (s) {
        ++s->calls;
        for (int j = 0; j < 2; ++j)
            if ((s->lower && p[j] < s->lower[j]) || (s->upper && p[j] > s->upper[j]))
                ++s->out_of_bounds;
    }
    r[0] = 10.0 * (p[1] - p[0] * p[0]);
    r[1] = 1.0 - p[0];
    if (jac) {
        jac[0] = -20.0 * p[0];
        jac[1] = 10.0;
        jac[2] = -1.0;
        jac[3] = 0.0;
    }
    return 0;
}

/* ---- callbacks that fail ----------------------------------------------------------------- */

static int always_fails(void *user, const double *p, double *r, double *jac)
{
    (void)p;
    (void)jac;
    ++*(int *)user;
    r[0] = 0.0;
    return 1;
}

/* r = log(p) (minimum at p = 1), undefined for p <= 0: the callback refuses such points.  From
 * p = 10 the Gauss-Newton step p - p log p = -13 leaves the domain, so the solver must treat the
 * failure as a rejected step and shrink the trust region. */
static int log_residual(void *user, const double *p, double *r, double *jac)
{
    if (!(p[0] > 0.0)) {
        ++*(int *)user;
        return 1;
    }
    r[0] = log(p[0]);
    if (jac)
        jac[0] = 1.0 / p[0];
    return 0;
}

/* A callback returning NaN residuals away from the start: treated as a failed evaluation. */
static int nan_residual(void *user, const double *p, double *r, double *jac)
{
    (void)user;
    r[0] = p[0] < 2.0 ? NAN : p[0] - 1.0;
    if (jac)
        jac[0] = 1.0;
    return 0;
}

static void test_exp_fit(void)
{
    exp_data d;
    exp_data_init(&d);
    mf_solver_options o;
    mf_solver_options_default(&o);
    CHECK(o.max_iterations == 100 && o.num_threads == 1 && o.trust_region == MF_SOLVER_LEVENBERG_MARQUARDT);
    CHECK(o.function_tolerance == 1e-12 && o.gradient_tolerance == 1e-12 && o.parameter_tolerance == 1e-12);

    double p[2] = {1.0, 0.0};
    mf_solver_summary s;
    mf_status st = mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s);
    CHECK(st == MF_OK);
    CHECK(s.converged == 1 && s.termination == MF_SOLVER_CONVERGENCE);
    CHECK(s.iterations > 0 && s.iterations <= o.max_iterations);
    CHECK(s.final_cost < s.initial_cost);
    CHECK(s.message[0] != '\0');
    /* Noise-free data, so the exact parameters are the solution.  The solver stops when a
     * tolerance of 1e-12 is met; near a zero-residual solution Gauss-Newton converges
     * quadratically, so the parameter error is then far below sqrt(1e-12) = 1e-6.  The floor is
     * the rounding of the data (~1e-16 relative) times the condition number of J (~1e2), i.e.
     * ~1e-14; 1e-10 leaves room for both while still proving convergence to the true point. */
    CHECK_REL(p[0], EXP_A, 1e-10);
    CHECK_REL(p[1], EXP_B, 1e-10);
    CHECK(s.final_cost < 1e-20);

    /* summary and options may be NULL. */
    double q[2] = {1.0, 0.0};
    st = mf_solver_least_squares(2, EXP_N, exp_residuals, &d, q, NULL, NULL, NULL, NULL);
    CHECK(st == MF_OK);
    CHECK_REL(q[0], EXP_A, 1e-10);
    CHECK_REL(q[1], EXP_B, 1e-10);

    /* Two threads give the same answer. */
    mf_solver_options o2 = o;
    o2.num_threads = 2;
    double t[2] = {1.0, 0.0};
    st = mf_solver_least_squares(2, EXP_N, exp_residuals, &d, t, NULL, NULL, &o2, &s);
    CHECK(st == MF_OK);
    CHECK_REL(t[0], EXP_A, 1e-10);
    CHECK_REL(t[1], EXP_B, 1e-10);
}

static void test_rosenbrock(void)
{
    mf_solver_options o;
    mf_solver_options_default(&o);
    for (int tr = 0; tr < 2; ++tr) {
        o.trust_region = tr ? MF_SOLVER_DOGLEG : MF_SOLVER_LEVENBERG_MARQUARDT;
        double p[2] = {-1.2, 1.0}; /* the classic start point */
        rosen_state rs = {0, 0, NULL, NULL};
        mf_solver_summary s;
        mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, &rs, p, NULL, NULL, &o, &s);
        CHECK(st == MF_OK);
        CHECK(s.converged == 1);
        CHECK(rs.calls > 0);
        /* Zero-residual minimum at (1, 1) with a well-conditioned Jacobian there (singular values
         * ~22 and ~0.45): quadratic convergence leaves an error near rounding (1e-16); 1e-10 is
         * a margin of many orders above it but far below any false stop (|x - 1| ~ 1e-3). */
        CHECK_ABS(p[0], 1.0, 1e-10);
        CHECK_ABS(p[1], 1.0, 1e-10);
    }
}

static void test_bounds(void)
{
    /* Rosenbrock with x0 <= 0.5: the unconstrained minimum (1, 1) is outside.  On the bound the
     * best point is x1 = x0^2 = 0.25 (r0 = 0), cost 1/2 (1 - 0.5)^2 = 0.125. */
    const double lower[2] = {-2.0, -INFINITY};
    const double upper[2] = {0.5, INFINITY};
    mf_solver_options o;
    mf_solver_options_default(&o);
    for (int tr = 0; tr < 2; ++tr) {
        o.trust_region = tr ? MF_SOLVER_DOGLEG : MF_SOLVER_LEVENBERG_MARQUARDT;
        double p[2] = {-1.2, 1.0};
        rosen_state rs = {0, 0, lower, upper};
        mf_solver_summary s;
        mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, &rs, p, lower, upper, &o, &s);
        CHECK(st == MF_OK);
        CHECK(rs.out_of_bounds == 0); /* the callback never sees a point outside the box */
        CHECK(p[0] <= 0.5 && p[0] >= -2.0);
        /* The active bound is reached exactly up to the convergence of the projected problem;
         * the free coordinate solves r0 = 0 with a Jacobian entry of 10, so 1e-9 is generous. */
        CHECK_ABS(p[0], 0.5, 1e-9);
        CHECK_ABS(p[1], 0.25, 1e-9);
        CHECK_ABS(s.final_cost, 0.125, 1e-9);
    }

    /* An active lower bound: x0 in [2, 3] (unconstrained optimum x0 = 1 is below), best point
     * x0 = 2, x1 = 4, cost 1/2 (1 - 2)^2 = 0.5.  Ceres alone crawls along the bound here and
     * stops at max_iterations with x1 ~ 3.9987; the bridge's re-solve with x0 held must finish. */
    {
        const double lo[2] = {2.0, -5.0}, hi[2] = {3.0, 5.0};
        double p[2] = {2.5, 0.0};
        rosen_state rs = {0, 0, lo, hi};
        mf_solver_summary s;
        mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, &rs, p, lo, hi, &o, &s);
        CHECK(st == MF_OK);
        CHECK(rs.out_of_bounds == 0);
        CHECK(p[0] == 2.0); /* on the bound exactly: Ceres clamps steps onto the box */
        CHECK_ABS(p[1], 4.0, 1e-9);
        CHECK_ABS(s.final_cost, 0.5, 1e-9);
    }

    /* Every parameter fixed by lower == upper: nothing to solve, the cost is reported. */
    {
        const double lo[2] = {0.3, 0.2}, hi[2] = {0.3, 0.2};
        double p[2] = {0.3, 0.2};
        mf_solver_summary s;
        mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, NULL, p, lo, hi, &o, &s);
        CHECK(st == MF_OK);
        CHECK(p[0] == 0.3 && p[1] == 0.2);
        CHECK(s.iterations == 0);
        CHECK_REL(s.final_cost, 0.5 * (1.1 * 1.1 + 0.7 * 0.7), 1e-14); /* r = (10 (0.2 - 0.09), 0.7) */
    }

    /* A start point on the bound, and a degenerate box lower == upper that fixes x0. */
    double lo2[2] = {0.3, -10.0}, hi2[2] = {0.3, 10.0};
    double p2[2] = {0.3, 0.0};
    rosen_state rs2 = {0, 0, lo2, hi2};
    mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, &rs2, p2, lo2, hi2, &o, NULL);
    CHECK(st == MF_OK);
    CHECK(p2[0] == 0.3);
    CHECK_ABS(p2[1], 0.09, 1e-9);
    CHECK(rs2.out_of_bounds == 0);
}

static void test_failing_callbacks(void)
{
    /* Fails everywhere, including the start: FAILURE, params left at the start point. */
    int fails = 0;
    double p[3] = {1.0, 2.0, 3.0};
    mf_solver_summary s;
    mf_status st = mf_solver_least_squares(3, 1, always_fails, &fails, p, NULL, NULL, NULL, &s);
    CHECK(st != MF_OK);
    CHECK(st == MF_ERR_NO_CONVERGENCE);
    CHECK(fails > 0);
    CHECK(s.converged == 0);
    CHECK(s.termination == MF_SOLVER_FAILURE);
    CHECK(s.message[0] != '\0');
    CHECK(p[0] == 1.0 && p[1] == 2.0 && p[2] == 3.0);

    /* Fails only outside its domain: the failure rejects the step, and the solve converges. */
    int rejected = 0;
    double q = 10.0;
    st = mf_solver_least_squares(1, 1, log_residual, &rejected, &q, NULL, NULL, NULL, &s);
    CHECK(st == MF_OK);
    CHECK(rejected > 0); /* the domain was actually hit */
    /* Zero residual, Jacobian 1 at the solution: error near rounding; 1e-10 as above. */
    CHECK_ABS(q, 1.0, 1e-10);

    /* NaN residuals count as failures too: solve from 5 towards 1 must stop at or above 2. */
    double u = 5.0;
    st = mf_solver_least_squares(1, 1, nan_residual, NULL, &u, NULL, NULL, NULL, &s);
    CHECK(isfinite(u) && u >= 2.0);
    CHECK(isfinite(s.final_cost));
    CHECK(st == MF_OK || st == MF_ERR_NO_CONVERGENCE);

    /* NaN residual at the start: FAILURE. */
    double w = 0.0;
    st = mf_solver_least_squares(1, 1, nan_residual, NULL, &w, NULL, NULL, NULL, &s);
    CHECK(st == MF_ERR_NO_CONVERGENCE);
    CHECK(s.termination == MF_SOLVER_FAILURE);
    CHECK(w == 0.0);
}

static void test_no_convergence(void)
{
    mf_solver_options o;
    mf_solver_options_default(&o);
    o.max_iterations = 2;
    double p[2] = {-1.2, 1.0};
    mf_solver_summary s;
    mf_status st = mf_solver_least_squares(2, 2, rosen_residuals, NULL, p, NULL, NULL, &o, &s);
    CHECK(st == MF_ERR_NO_CONVERGENCE);
    CHECK(s.converged == 0);
    CHECK(s.termination == MF_SOLVER_NO_CONVERGENCE);
    CHECK(s.iterations <= 2);
    CHECK(isfinite(p[0]) && isfinite(p[1]));
    CHECK(s.final_cost <= s.initial_cost);
    CHECK_ABS(s.initial_cost, 0.5 * (4.4 * 4.4 + 2.2 * 2.2), 1e-12); /* r = (10 (1 - 1.44), 2.2) */
}

static void test_invalid_arguments(void)
{
    exp_data d;
    exp_data_init(&d);
    mf_solver_options o;
    mf_solver_summary s;
    const double start[2] = {1.0, 0.0};
    double p[2];
#define EXPECT_DOMAIN(call)                                                                                     \
    do {                                                                                                        \
        memcpy(p, start, sizeof p);                                                                             \
        memset(&s, 0x55, sizeof s);                                                                             \
        mf_status st_ = (call);                                                                                 \
        CHECK(st_ == MF_ERR_DOMAIN);                                                                            \
        CHECK(memcmp(p, start, sizeof p) == 0);                                                                 \
        CHECK(s.termination == MF_SOLVER_NOT_RUN && s.converged == 0 && s.iterations == 0);                     \
        CHECK(s.message[0] != '\0' && memchr(s.message, '\0', sizeof s.message) != NULL);                     \
    } while (0)

    mf_solver_options_default(&o);
    EXPECT_DOMAIN(mf_solver_least_squares(0, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    EXPECT_DOMAIN(mf_solver_least_squares(-1, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    EXPECT_DOMAIN(mf_solver_least_squares(2, 0, exp_residuals, &d, p, NULL, NULL, &o, &s));
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, NULL, &d, p, NULL, NULL, &o, &s));
    EXPECT_DOMAIN(mf_solver_least_squares(100000, 100000, exp_residuals, &d, p, NULL, NULL, &o, &s));
    CHECK(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, NULL, NULL, NULL, &o, &s) == MF_ERR_DOMAIN);

    /* Bounds: lower > upper, NaN, start outside, a side excluding every finite value. */
    {
        const double lo[2] = {0.0, 0.0}, hi[2] = {-1.0, 1.0};
        EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, lo, hi, &o, &s));
    }
    {
        const double lo[2] = {NAN, -1.0};
        EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, lo, NULL, &o, &s));
    }
    {
        const double lo[2] = {2.0, -1.0}; /* start p0 = 1 < 2 */
        EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, lo, NULL, &o, &s));
    }
    {
        const double hi[2] = {5.0, -0.5}; /* start p1 = 0 > -0.5 */
        EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, hi, &o, &s));
    }
    {
        const double lo[2] = {INFINITY, -1.0};
        EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, lo, NULL, &o, &s));
    }
    /* A non-finite start point. */
    {
        double bad[2] = {NAN, 0.0};
        CHECK(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, bad, NULL, NULL, &o, &s) == MF_ERR_DOMAIN);
        CHECK(isnan(bad[0]) && bad[1] == 0.0);
        bad[0] = INFINITY;
        CHECK(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, bad, NULL, NULL, &o, &s) == MF_ERR_DOMAIN);
    }
    /* Options out of range. */
    mf_solver_options_default(&o);
    o.max_iterations = -1;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    mf_solver_options_default(&o);
    o.num_threads = 0;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    mf_solver_options_default(&o);
    o.trust_region = 2;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    mf_solver_options_default(&o);
    o.function_tolerance = -1e-3;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    mf_solver_options_default(&o);
    o.gradient_tolerance = NAN;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
    mf_solver_options_default(&o);
    o.parameter_tolerance = INFINITY;
    EXPECT_DOMAIN(mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p, NULL, NULL, &o, &s));
#undef EXPECT_DOMAIN

    mf_solver_options_default(NULL); /* no crash */
}

static void test_determinism(void)
{
    exp_data d;
    exp_data_init(&d);
    const double lower[2] = {0.0, -5.0}, upper[2] = {10.0, 5.0};
    double p1[2] = {1.0, 0.0}, p2[2] = {1.0, 0.0};
    mf_solver_summary s1, s2;
    memset(&s1, 0, sizeof s1);
    memset(&s2, 0, sizeof s2);
    mf_status a = mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p1, lower, upper, NULL, &s1);
    mf_status b = mf_solver_least_squares(2, EXP_N, exp_residuals, &d, p2, lower, upper, NULL, &s2);
    CHECK(a == MF_OK && b == MF_OK);
    CHECK(memcmp(p1, p2, sizeof p1) == 0);
    CHECK(memcmp(&s1.final_cost, &s2.final_cost, sizeof(double)) == 0);
    CHECK(memcmp(&s1.initial_cost, &s2.initial_cost, sizeof(double)) == 0);
    CHECK(s1.iterations == s2.iterations);

    double r1[2] = {-1.2, 1.0}, r2[2] = {-1.2, 1.0};
    a = mf_solver_least_squares(2, 2, rosen_residuals, NULL, r1, NULL, NULL, NULL, NULL);
    b = mf_solver_least_squares(2, 2, rosen_residuals, NULL, r2, NULL, NULL, NULL, NULL);
    CHECK(a == MF_OK && b == MF_OK);
    CHECK(memcmp(r1, r2, sizeof r1) == 0);
}

int main(void)
{
    mf_test_seed(0); /* nothing random here */
    test_exp_fit();
    test_rosenbrock();
    test_bounds();
    test_failing_callbacks();
    test_no_convergence();
    test_invalid_arguments();
    test_determinism();
    MF_TEST_MAIN_END();
}
