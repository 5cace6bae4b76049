// mf_solver_ceres.cpp -- the C API of mf_solver.h over Ceres 2.1.
//
// One parameter block of n_params doubles, one residual block of n_residuals residuals whose
// cost function calls the C callback with analytic Jacobians.  Dense QR, LM or dogleg, silent.
// No exception crosses the C boundary.
//
// Bounds.  Ceres handles box bounds only by projecting each trust region step onto the box, so
// once a parameter sits on a bound, steps are clipped and the solver often stops early on the
// parameter tolerance with the free parameters still far from their optimum (Rosenbrock with
// x0 <= 0.5 stops with x1 off by 2e-3), or crawls along the bound until max_iterations.  We
// therefore polish: after a solve that ends with a usable point, the parameters on a bound
// whose gradient points out of the box are held fixed (SubsetManifold) and the rest re-solved,
// until the active set no longer changes.  Parameters with
// lower == upper (which Ceres rejects as infeasible) are held fixed throughout.

#include "mfkit/fit/mf_solver.h"

#include <ceres/ceres.h>
#include <glog/logging.h>

#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <new>
#include <string>
#include <vector>

namespace {

// A Ceres cost function that forwards to the C callback.  Ceres lays out jacobians[0] exactly
// as the callback does: row-major, n_residuals x n_params.
class CallbackCost final : public ceres::CostFunction {
public:
    CallbackCost(int n_params, int n_residuals, mf_solver_residual_fn fn, void *user)
        : n_params_(n_params), n_residuals_(n_residuals), fn_(fn), user_(user)
    {
        set_num_residuals(n_residuals);
        mutable_parameter_block_sizes()->push_back(n_params);
    }

    bool Evaluate(double const *const *parameters, double *residuals, double **jacobians) const override
    {
        return evaluate(parameters[0], residuals, (jacobians != nullptr) ? jacobians[0] : nullptr);
    }

    // The callback, with non-finite outputs counted as a failure (they would poison the trust
    // region).
    bool evaluate(const double *x, double *residuals, double *jac) const
    {
        if (fn_(user_, x, residuals, jac) != 0)
            return false;
        for (int i = 0; i < n_residuals_; ++i)
            if (!std::isfinite(residuals[i]))
                return false;
        if (jac != nullptr) {
            const size_t n = static_cast<size_t>(n_residuals_) * static_cast<size_t>(n_params_);
            for (size_t k = 0; k < n; ++k)
                if (!std::isfinite(jac[k]))
                    return false;
        }
        return true;
    }

private:
    int n_params_;
    int n_residuals_;
    mf_solver_residual_fn fn_;
    void *user_;
};

// Ceres logs every FAILURE termination with glog's LOG(ERROR) whatever its logging_type, and
// glog then writes to stderr.  While any solve runs, raise glog's minloglevel to FATAL (never
// lower it), and restore the caller's value when the last concurrent solve ends.
std::mutex quiet_mutex;
int quiet_users = 0;
int quiet_saved_level = 0;

class QuietGlog {
public:
    QuietGlog()
    {
        std::lock_guard<std::mutex> lock(quiet_mutex);
        if (quiet_users++ == 0) {
            quiet_saved_level = FLAGS_minloglevel;
            if (FLAGS_minloglevel < google::GLOG_FATAL)
                FLAGS_minloglevel = google::GLOG_FATAL;
        }
    }
    ~QuietGlog()
    {
        std::lock_guard<std::mutex> lock(quiet_mutex);
        if (--quiet_users == 0)
            FLAGS_minloglevel = quiet_saved_level;
    }
    QuietGlog(const QuietGlog &) = delete;
    QuietGlog &operator=(const QuietGlog &) = delete;
};

void set_message(mf_solver_summary *summary, const char *text)
{
    if (summary == nullptr)
        return;
    std::snprintf(summary->message, sizeof summary->message, "%s", text);
    // One line: Ceres messages occasionally contain newlines.
    for (char *c = summary->message; *c != '\0'; ++c)
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

void summary_not_run(mf_solver_summary *summary, const char *why)
{
    if (summary == nullptr)
        return;
    summary->iterations = 0;
    summary->initial_cost = NAN;
    summary->final_cost = NAN;
    summary->converged = 0;
    summary->termination = MF_SOLVER_NOT_RUN;
    set_message(summary, why);
}

int map_termination(ceres::TerminationType t)
{
    switch (t) {
    case ceres::CONVERGENCE: return MF_SOLVER_CONVERGENCE;
    case ceres::NO_CONVERGENCE: return MF_SOLVER_NO_CONVERGENCE;
    case ceres::FAILURE: return MF_SOLVER_FAILURE;
    case ceres::USER_SUCCESS: return MF_SOLVER_USER_SUCCESS;
    case ceres::USER_FAILURE: return MF_SOLVER_USER_FAILURE;
    }
    return MF_SOLVER_FAILURE;
}

bool valid_tolerance(double t) { return std::isfinite(t) && t >= 0.0; }

// Checks the arguments; returns nullptr if they are valid, else a reason.
const char *check_arguments(int n_params, int n_residuals, mf_solver_residual_fn fn, const double *params,
                            const double *lower, const double *upper, const mf_solver_options &o)
{
    if (n_params < 1)
        return "n_params must be >= 1";
    if (n_residuals < 1)
        return "n_residuals must be >= 1";
    if (static_cast<long long>(n_params) * static_cast<long long>(n_residuals) > INT_MAX)
        return "n_params * n_residuals is too large";
    if (fn == nullptr)
        return "the residual callback is NULL";
    if (params == nullptr)
        return "params is NULL";
    if (o.max_iterations < 0)
        return "max_iterations must be >= 0";
    if (!valid_tolerance(o.function_tolerance) || !valid_tolerance(o.gradient_tolerance) ||
        !valid_tolerance(o.parameter_tolerance))
        return "tolerances must be finite and >= 0";
    if (o.num_threads < 1)
        return "num_threads must be >= 1";
    if (o.trust_region != MF_SOLVER_LEVENBERG_MARQUARDT && o.trust_region != MF_SOLVER_DOGLEG)
        return "trust_region must be MF_SOLVER_LEVENBERG_MARQUARDT or MF_SOLVER_DOGLEG";
    for (int j = 0; j < n_params; ++j) {
        if (!std::isfinite(params[j]))
            return "the start point is not finite";
        const double lo = lower ? lower[j] : -INFINITY;
        const double hi = upper ? upper[j] : INFINITY;
        if (std::isnan(lo) || std::isnan(hi))
            return "a bound is NaN";
        if (lo > hi)
            return "a lower bound exceeds its upper bound";
        if (lo == INFINITY || hi == -INFINITY)
            return "a bound excludes every finite value";
        if (!(lo <= params[j] && params[j] <= hi))
            return "the start point is outside the bounds";
    }
    return nullptr;
}

// The problem and the options shared by every phase of one solve.
struct Solve {
    int n_params, n_residuals;
    mf_solver_residual_fn fn;
    void *user;
    const double *lower, *upper;
    ceres::Solver::Options options;
};

// One Ceres solve from x (updated in place if the result is usable) with the parameters whose
// `fixed` flag is set held constant.  At least one parameter must be free.
ceres::Solver::Summary run_phase(const Solve &s, std::vector<double> &x, const std::vector<char> &fixed,
                                 int max_iterations)
{
    std::vector<double> y = x;
    ceres::Problem::Options problem_options;
    problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(problem_options);
    problem.AddResidualBlock(new CallbackCost(s.n_params, s.n_residuals, s.fn, s.user), nullptr, y.data());
    std::vector<int> constant;
    for (int j = 0; j < s.n_params; ++j) {
        if (fixed[j]) {
            constant.push_back(j);
            continue;
        }
        // Ceres's own "unbounded" is +-DBL_MAX; keep infinities out of its arithmetic.
        if (s.lower != nullptr && s.lower[j] > -DBL_MAX)
            problem.SetParameterLowerBound(y.data(), j, s.lower[j]);
        if (s.upper != nullptr && s.upper[j] < DBL_MAX)
            problem.SetParameterUpperBound(y.data(), j, s.upper[j]);
    }
    if (!constant.empty())
        problem.SetManifold(y.data(), new ceres::SubsetManifold(s.n_params, constant));

    ceres::Solver::Options options = s.options;
    options.max_num_iterations = max_iterations;
    ceres::Solver::Summary cs;
    ceres::Solve(options, &problem, &cs);
    // A usable solution (CONVERGENCE, NO_CONVERGENCE, USER_SUCCESS) is the last accepted point;
    // after a FAILURE Ceres's parameters are undefined, so x keeps its value.
    if (cs.IsSolutionUsable())
        x = y;
    return cs;
}

// Trust region steps of a Ceres solve (its iteration list starts with the start point).
int steps_taken(const ceres::Solver::Summary &cs)
{
    return cs.iterations.empty() ? 0 : static_cast<int>(cs.iterations.size()) - 1;
}

} // namespace

extern "C" void mf_solver_options_default(mf_solver_options *o)
{
    if (o == nullptr)
        return;
    o->max_iterations = 100;
    o->function_tolerance = 1e-12;
    o->gradient_tolerance = 1e-12;
    o->parameter_tolerance = 1e-12;
    o->num_threads = 1;
    o->trust_region = MF_SOLVER_LEVENBERG_MARQUARDT;
}

extern "C" mf_status mf_solver_least_squares(int n_params, int n_residuals, mf_solver_residual_fn fn, void *user,
                                             double *params, const double *lower, const double *upper,
                                             const mf_solver_options *opt, mf_solver_summary *summary)
{
    try {
        mf_solver_options o;
        mf_solver_options_default(&o);
        if (opt != nullptr)
            o = *opt;

        if (const char *why = check_arguments(n_params, n_residuals, fn, params, lower, upper, o)) {
            summary_not_run(summary, why);
            return MF_ERR_DOMAIN;
        }

        Solve s{n_params, n_residuals, fn, user, lower, upper, ceres::Solver::Options()};
        s.options.minimizer_type = ceres::TRUST_REGION;
        s.options.trust_region_strategy_type =
            (o.trust_region == MF_SOLVER_DOGLEG) ? ceres::DOGLEG : ceres::LEVENBERG_MARQUARDT;
        s.options.linear_solver_type = ceres::DENSE_QR;
        s.options.max_num_iterations = o.max_iterations;
        s.options.function_tolerance = o.function_tolerance;
        s.options.gradient_tolerance = o.gradient_tolerance;
        s.options.parameter_tolerance = o.parameter_tolerance;
        s.options.num_threads = o.num_threads;
        s.options.minimizer_progress_to_stdout = false;
        s.options.logging_type = ceres::SILENT;
        std::string why;
        if (!s.options.IsValid(&why)) {
            summary_not_run(summary, why.c_str());
            return MF_ERR_DOMAIN;
        }

        // Work on a copy: params changes only at the end.
        std::vector<double> x(params, params + n_params);
        std::vector<char> fixed(static_cast<size_t>(n_params), 0);
        int n_fixed = 0;
        for (int j = 0; j < n_params; ++j)
            if (lower != nullptr && upper != nullptr && lower[j] == upper[j]) {
                fixed[j] = 1;
                ++n_fixed;
            }

        const CallbackCost cost(n_params, n_residuals, fn, user);
        std::vector<double> r(static_cast<size_t>(n_residuals));
        std::vector<double> jac(static_cast<size_t>(n_residuals) * static_cast<size_t>(n_params));

        int termination, iterations = 0;
        double initial_cost, final_cost;
        std::string message;
        if (n_fixed == n_params) {
            // Nothing to optimise: report the cost at the (only feasible) start point.
            if (cost.evaluate(x.data(), r.data(), nullptr)) {
                double c = 0.0;
                for (double v : r)
                    c += v * v;
                initial_cost = final_cost = 0.5 * c;
                termination = MF_SOLVER_CONVERGENCE;
                message = "every parameter is fixed by lower == upper";
            } else {
                initial_cost = final_cost = NAN;
                termination = MF_SOLVER_FAILURE;
                message = "the residual callback failed at the start point";
            }
        } else {
            QuietGlog quiet;
            ceres::Solver::Summary cs = run_phase(s, x, fixed, o.max_iterations);
            iterations = steps_taken(cs);
            termination = map_termination(cs.termination_type);
            // Ceres reports -1 for costs it could not evaluate.
            initial_cost = cs.initial_cost >= 0.0 ? cs.initial_cost : NAN;
            final_cost = cs.final_cost >= 0.0 ? cs.final_cost : NAN;
            message = cs.message;

            // Polish a bounded solve (see the top of this file): at most n_params + 1 more Ceres
            // solves, each with its own max_iterations budget.
            std::vector<char> active = fixed;
            for (int round = 0; (lower != nullptr || upper != nullptr) && o.max_iterations > 0 &&
                                (termination == MF_SOLVER_CONVERGENCE || termination == MF_SOLVER_NO_CONVERGENCE) &&
                                round <= n_params;
                 ++round) {
                if (!cost.evaluate(x.data(), r.data(), jac.data()))
                    break;
                std::vector<char> next = fixed;
                int n_next = 0;
                for (int j = 0; j < n_params; ++j) {
                    double g = 0.0; // d cost / d x_j = sum_i r_i J_ij
                    for (int i = 0; i < n_residuals; ++i)
                        g += r[i] * jac[static_cast<size_t>(i) * n_params + j];
                    if ((lower != nullptr && x[j] <= lower[j] && g > 0.0) ||
                        (upper != nullptr && x[j] >= upper[j] && g < 0.0))
                        next[j] = 1;
                    n_next += next[j] ? 1 : 0;
                }
                // Stop when the active set is stable, or every parameter is held by a bound
                // whose gradient points outwards (a vertex satisfying the optimality conditions).
                if (next == active || n_next == n_params)
                    break;
                std::vector<double> y = x;
                ceres::Solver::Summary ps = run_phase(s, y, next, o.max_iterations);
                if (!ps.IsSolutionUsable() || !(ps.final_cost <= final_cost))
                    break;
                x = y;
                iterations += steps_taken(ps);
                termination = map_termination(ps.termination_type);
                final_cost = ps.final_cost;
                message = ps.message + " (after holding parameters on active bounds fixed)";
                active = next;
            }
        }

        const bool converged = termination == MF_SOLVER_CONVERGENCE || termination == MF_SOLVER_USER_SUCCESS;
        std::memcpy(params, x.data(), sizeof(double) * static_cast<size_t>(n_params));
        if (summary != nullptr) {
            summary->iterations = iterations;
            summary->initial_cost = initial_cost;
            summary->final_cost = final_cost;
            summary->converged = converged ? 1 : 0;
            summary->termination = termination;
            set_message(summary, message.c_str());
        }
        return converged ? MF_OK : MF_ERR_NO_CONVERGENCE;
    } catch (const std::bad_alloc &) {
        summary_not_run(summary, "memory allocation failed");
        return MF_ERR_ALLOC;
    } catch (...) {
        summary_not_run(summary, "internal error: an exception was thrown inside the solver");
        return MF_ERR_INTERNAL;
    }
}
