// What the Ceres solvers of the fit and the stack optimiser report while they run: progress
// per iteration, and a stop when the run is cancelled (Ctrl-C, --max-time): an iteration is
// the longest stretch a stage goes without looking (#21 item 8).
#pragma once

#include <ceres/iteration_callback.h>

#include <algorithm>
#include <string_view>

#include "nonplanar/context.hpp"

namespace nonplanar::nurbs {

class SolverProgress final : public ceres::IterationCallback {
 public:
  /// Reports `stage` at from + (to − from) · iteration / max_iterations (an empty stage: no
  /// report, only the stop).
  SolverProgress(const Context& ctx, std::string_view stage, double from, double to,
                 int max_iterations)
      : ctx_(ctx), stage_(stage), from_(from), to_(to), max_(std::max(1, max_iterations)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (!stage_.empty())
      ctx_.progress(stage_, from_ + (to_ - from_) * std::min(1.0, double(s.iteration) / max_));
    return ctx_.cancelled() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const Context& ctx_;
  std::string_view stage_;
  double from_, to_;
  int max_;
};

}  // namespace nonplanar::nurbs
