// dynamap evaluate: ATE/RPE of an estimated trajectory against ground truth, as the TUM
// RGB-D benchmark scripts compute them.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
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
  std::string save_alignment_path;
  std::string alignment_path;
};

constexpr const char* kAlignmentHeader =
    "# dynamap evaluate alignment: p_gt = scale * R * p_est + t; scale r00 r01 r02 r10 r11 r12 "
    "r20 r21 r22 tx ty tz\n";

void writeAlignment(const std::string& path, const Alignment& a) {
  std::ofstream out(path);
  out << kAlignmentHeader << std::setprecision(17) << a.scale;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out << ' ' << a.R(r, c);
  }
  out << ' ' << a.t.x() << ' ' << a.t.y() << ' ' << a.t.z() << '\n';
  if (!out) throw std::runtime_error(path + ": cannot write");
}

/// What writeAlignment() wrote; EvaluationError naming the file otherwise.
Alignment readAlignment(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw EvaluationError(path + ": cannot read the alignment");
  std::string line;
  while (std::getline(in, line) && (line.empty() || line[0] == '#')) {
  }
  std::istringstream fields(line);
  Alignment a;
  fields >> a.scale;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) fields >> a.R(r, c);
  }
  fields >> a.t.x() >> a.t.y() >> a.t.z();
  const bool rotation = (a.R.transpose() * a.R - Eigen::Matrix3d::Identity()).norm() < 1e-6;
  if (!fields || !std::isfinite(a.scale) || a.scale <= 0.0 || !a.t.allFinite() || !rotation) {
    throw EvaluationError(path + ": not an alignment (13 numbers: scale > 0, a rotation, t)");
  }
  return a;
}

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
  if (!args.alignment_path.empty()) options.given_alignment = readAlignment(args.alignment_path);

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
  if (!args.save_alignment_path.empty()) {
    writeAlignment(args.save_alignment_path, evaluation.ate.alignment);
  }
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
  cmd->add_option("--save-alignment", args->save_alignment_path,
                  "write the ATE alignment used (p_gt = scale R p_est + t) to this file");
  cmd->add_option("--alignment", args->alignment_path,
                  "apply this alignment (a --save-alignment file, e.g. of the run whose saved map "
                  "a --load-map run started in) instead of estimating one");
  cmd->callback([args, exit_code] { *exit_code = runEvaluate(*args); });
}

}  // namespace dynamap
