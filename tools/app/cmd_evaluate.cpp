// dynamap evaluate: ATE/RPE of an estimated trajectory against ground truth, as the TUM
// RGB-D benchmark scripts compute them.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "trajectory_eval.hpp"
#include "trajectory_io.hpp"
#include "trajectory_plot.hpp"

namespace dynamap {
namespace {

struct EvaluateArgs {
  std::string gt_path;
  std::string est_path;
  bool json = false;
  std::string plot_path;
  std::string align = "se3";
  double rpe_delta = 1.0;
  std::string rpe_unit = "s";
  std::string rpe_pairs_path;
};

/// One line per RPE pair: the later pose's stamp, translation (m) and rotation (deg) error.
void writeRpePairs(const std::string& path, const RpeResult& rpe) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out << "# stamp_s trans_error_m rot_error_deg (RPE, delta " << rpe.delta
      << (rpe.unit == RpeDeltaUnit::kFrames ? " frames" : " s") << ")\n";
  out << std::fixed;
  for (std::size_t i = 0; i < rpe.timestamps_s.size(); ++i) {
    out << std::setprecision(6) << rpe.timestamps_s[i] << ' ' << std::setprecision(6)
        << rpe.trans_errors_m[i] << ' ' << rpe.rot_errors_deg[i] << '\n';
  }
  if (!out) throw std::runtime_error(path + ": write failed");
}

int runEvaluate(const EvaluateArgs& args) {
  TrajectoryEvalOptions options;
  options.alignment = args.align == "sim3" ? AlignmentKind::kSim3 : AlignmentKind::kSe3;
  options.rpe_delta = args.rpe_delta;
  options.rpe_unit = args.rpe_unit == "f" ? RpeDeltaUnit::kFrames : RpeDeltaUnit::kSeconds;

  const std::vector<TimedPose> gt = readTrajectory(args.gt_path);
  const std::vector<TimedPose> est = readTrajectory(args.est_path);
  TrajectoryEvaluation evaluation;
  try {
    evaluation = evaluateTrajectories(gt, est, options);
  } catch (const EvaluationError& e) {
    throw EvaluationError(args.est_path + " vs " + args.gt_path + ": " + e.what());
  }
  if (!args.plot_path.empty()) {
    writeTrajectoryPlot(args.plot_path, gt, evaluation.ate);
  }
  if (!args.rpe_pairs_path.empty()) writeRpePairs(args.rpe_pairs_path, evaluation.rpe);
  if (args.json) {
    std::cout << evaluationToJson(evaluation) << "\n";
  } else {
    std::cout << "ground truth: " << args.gt_path << " (" << gt.size() << " poses)\n"
              << "estimate:     " << args.est_path << " (" << est.size() << " poses)\n"
              << evaluationToTable(evaluation);
    if (!args.plot_path.empty()) std::cout << "plot:         " << args.plot_path << "\n";
  }
  return 0;
}

}  // namespace

void addEvaluateCommand(CLI::App& app, int* exit_code) {
  auto* cmd = app.add_subcommand(
      "evaluate", "ATE/RPE of an estimated trajectory vs ground truth (TUM benchmark definitions)");
  auto args = std::make_shared<EvaluateArgs>();
  cmd->add_option("--gt", args->gt_path, "ground-truth trajectory (TUM format)")->required();
  cmd->add_option("--est", args->est_path, "estimated trajectory (TUM format)")->required();
  cmd->add_flag("--json", args->json, "print one JSON object instead of a table");
  cmd->add_option("--plot", args->plot_path, "write a top-view plot (PNG) of both trajectories");
  cmd->add_option("--align", args->align, "ATE alignment: se3 (rigid) or sim3 (with scale)")
      ->check(CLI::IsMember({"se3", "sim3"}))
      ->capture_default_str();
  cmd->add_option("--rpe-delta", args->rpe_delta, "RPE fixed delta")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--rpe-unit", args->rpe_unit, "RPE delta unit: s (seconds) or f (frames)")
      ->check(CLI::IsMember({"s", "f"}))
      ->capture_default_str();
  cmd->add_option("--rpe-pairs", args->rpe_pairs_path,
                  "write every RPE pair (stamp, translation m, rotation deg) to this file");
  cmd->callback([args, exit_code] { *exit_code = runEvaluate(*args); });
}

}  // namespace dynamap
