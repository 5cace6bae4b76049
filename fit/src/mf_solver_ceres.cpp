// mf_solver_ceres.cpp -- the C API of mf_solver.h over Ceres 2.1.
//
// One parameter block of n_params doubles, one residual block of n_residuals residuals whose
// cost function calls the C callback with analytic Jacobians.  Dense QR, LM or dogleg, silent.
// No exception crosses the C boundary.

#include "mfkit/mf_solver.h"

#include <ceres/ceres.h>

#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
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
        double *jac = (jacobians != nullptr) ? jacobians[0] : nullptr;
        if (fn_(user_, parameters[0], residuals, jac) != 0)
            return false;
        // A non-finite value would poison the trust region: treat it as a failed evaluation.
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

        // Work on a copy: params changes only when Ceres returns.
        std::vector<double> x(params, params + n_params);

        ceres::Problem::Options problem_options;
        problem_options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
        ceres::Problem problem(problem_options);
        problem.AddResidualBlock(new CallbackCost(n_params, n_residuals, fn, user), nullptr, x.data());
        for (int j = 0; j < n_params; ++j) {
            // Ceres's own "unbounded" is +-DBL_MAX; keep infinities out of its arithmetic.
            if (lower != nullptr && lower[j] > -DBL_MAX)
                problem.SetParameterLowerBound(x.data(), j, lower[j]);
            if (upper != nullptr && upper[j] < DBL_MAX)
                problem.SetParameterUpperBound(x.data(), j, upper[j]);
        }

        ceres::Solver::Options so;
        so.minimizer_type = ceres::TRUST_REGION;
        so.trust_region_strategy_type =
            (o.trust_region == MF_SOLVER_DOGLEG) ? ceres::DOGLEG : ceres::LEVENBERG_MARQUARDT;
        so.linear_solver_type = ceres::DENSE_QR;
        so.max_num_iterations = o.max_iterations;
        so.function_tolerance = o.function_tolerance;
        so.gradient_tolerance = o.gradient_tolerance;
        so.parameter_tolerance = o.parameter_tolerance;
        so.num_threads = o.num_threads;
        so.minimizer_progress_to_stdout = false;
        so.logging_type = ceres::SILENT;
        std::string why;
        if (!so.IsValid(&why)) {
            summary_not_run(summary, why.c_str());
            return MF_ERR_DOMAIN;
        }

        ceres::Solver::Summary cs;
        ceres::Solve(so, &problem, &cs);

        const int termination = map_termination(cs.termination_type);
        const bool converged = termination == MF_SOLVER_CONVERGENCE || termination == MF_SOLVER_USER_SUCCESS;

        // A usable solution (CONVERGENCE, NO_CONVERGENCE, USER_SUCCESS) is the last accepted point;
        // after a FAILURE Ceres's x is undefined, so params keeps the start point.
        if (cs.IsSolutionUsable())
            std::memcpy(params, x.data(), sizeof(double) * static_cast<size_t>(n_params));
        if (summary != nullptr) {
            const int steps = (cs.num_successful_steps > 0 ? cs.num_successful_steps : 0) +
                              (cs.num_unsuccessful_steps > 0 ? cs.num_unsuccessful_steps : 0);
            summary->iterations = steps;
            // Ceres reports -1 for costs it could not evaluate.
            summary->initial_cost = cs.initial_cost >= 0.0 ? cs.initial_cost : NAN;
            summary->final_cost = cs.final_cost >= 0.0 ? cs.final_cost : NAN;
            summary->converged = converged ? 1 : 0;
            summary->termination = termination;
            set_message(summary, cs.message.c_str());
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
