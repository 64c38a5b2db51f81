// The least-squares solver's own log kept off the user's terminal.
//
// Ceres writes its internal retries to glog's stderr ("Linear solver
// failure", "Terminating: … invalid steps") even with
// Solver::Options::logging_type SILENT; an analysis reads the solver's
// Summary and says in its report what a failed fit means, so those lines
// only interleave with `insdiag analyze --progress` and the server's log.
#pragma once

namespace insdiag::engine::numerics {

// Raises glog's minimum level to FATAL for the process, once (later calls do
// nothing). Called before every Ceres solve.
void QuietSolverLog();

}  // namespace insdiag::engine::numerics
