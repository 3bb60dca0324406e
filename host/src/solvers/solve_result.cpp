#include "lightstage/host/solvers/solve_result.hpp"

namespace lightstage {

nlohmann::json SolveSummary::to_json() const {
  return {{"method", method},
          {"pixels_in_mask", pixels_in_mask},
          {"pixels_solved", pixels_solved},
          {"pixels_rejected_too_few_observations", pixels_rejected_too_few_observations},
          {"pixels_rejected_degenerate", pixels_rejected_degenerate},
          {"seconds", seconds},
          {"message", message}};
}

}  // namespace lightstage
