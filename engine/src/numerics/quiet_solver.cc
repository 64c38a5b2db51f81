#include "insdiag/engine/numerics/quiet_solver.h"

#include <glog/logging.h>

#include <mutex>

namespace insdiag::engine::numerics {

void QuietSolverLog() {
  static std::once_flag once;
  std::call_once(once, [] { FLAGS_minloglevel = google::GLOG_FATAL; });
}

}  // namespace insdiag::engine::numerics
