#pragma once

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "trajectory_io.hpp"

namespace dynamap {

/// The evaluation cannot be computed (e.g. no associated pose pairs).
class EvaluationError : public std::runtime_error {
 public:
  using runtime_error::runtime_error;
};

enum class AlignmentKind { kSe3, kSim3 };
enum class RpeDeltaUnit { kSeconds, kFrames };

const char* toString(AlignmentKind kind);  ///< "se3" | "sim3"
const char* toString(RpeDeltaUnit unit);   ///< "s" | "f"

/// p_gt ~= scale * R * p_est + t.
struct Alignment {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double scale = 1.0;
};
/// Options. Defaults are those of the TUM benchmark scripts
/// (evaluate_ate.py; evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s).
struct TrajectoryEvalOptions {
  double max_time_diff_s = 0.02;  ///< ATE association window (strict <)
  AlignmentKind alignment = AlignmentKind::kSe3;
  double rpe_delta = 1.0;
  RpeDeltaUnit rpe_unit = RpeDeltaUnit::kSeconds;
  /// Applied as it is instead of the least-squares alignment (e.g. another run's, to judge a
  /// run that started in that run's saved map in its frame); `alignment` is then unused.
  std::optional<Alignment> given_alignment;
};

/// Summary of a list of errors (numpy semantics: median averages the two middle values,
/// std is the population standard deviation). All NaN when `count` is 0.
struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std_dev = 0.0;  ///< population standard deviation
  double min = 0.0;
  double max = 0.0;
};
ErrorStats computeErrorStats(const std::vector<double>& errors);

/// Horn/Umeyama least-squares alignment of `est` onto `gt` (3xN each, N >= 1) via the SVD of
/// the cross-covariance of the centred sets, with the reflection fix. with_scale -> Sim(3).
Alignment alignPositions(const Eigen::Matrix3Xd& est, const Eigen::Matrix3Xd& gt, bool with_scale);

struct AteResult {
  std::size_t pairs = 0;
  ErrorStats error_m;
  Alignment alignment;
  bool with_scale = false;
  bool alignment_given = false;  ///< TrajectoryEvalOptions::given_alignment was applied
  // Per associated pair, sorted by ground-truth time:
  std::vector<double> timestamps_s;             ///< ground-truth stamps
  std::vector<Eigen::Vector3d> gt_positions_m;  ///< ground-truth positions
  std::vector<Eigen::Vector3d> est_aligned_m;   ///< aligned estimated positions
  std::vector<double> errors_m;                 ///< |gt - aligned est|
};

struct RpeResult {
  std::size_t pairs = 0;
  double delta = 1.0;
  RpeDeltaUnit unit = RpeDeltaUnit::kSeconds;
  ErrorStats trans_m;
  ErrorStats rot_deg;
  // Per pair, in the estimate's order:
  std::vector<double> timestamps_s;    ///< the estimated stamp of the pair's later pose
  std::vector<double> trans_errors_m;  ///< translation of the relative-motion error
  std::vector<double> rot_errors_deg;  ///< its rotation angle
};

struct TrajectoryEvaluation {
  AteResult ate;
  RpeResult rpe;
};

/// Rigid alignment of the estimate onto the ground truth from whole poses, for comparing maps
/// (not the benchmark's ATE alignment): maximises sum |p_gt - R p_est - t|^2 +
/// rotation_weight_m2 * |R_gt - R R_est|_F^2 over associated pairs, one SVD of
/// cov(p_gt, p_est) + rotation_weight_m2 * sum R_gt R_est^T. Positions alone leave the rotation
/// about a (nearly) straight path free; the rest of the map swings with it, the camera
/// orientations pin it down. Throws EvaluationError when fewer than 2 pairs associate.
Alignment alignPoses(const std::vector<TimedPose>& gt, const std::vector<TimedPose>& est,
                     double max_time_diff_s, double rotation_weight_m2 = 1.0);

/// ATE of position pairs already associated (column k of `est` with column k of `gt`, N >= 1):
/// alignment, per-pair errors and their statistics; `timestamps_s` stays empty. computeAte is
/// this after associating by time.
/// `given`: that alignment instead of the least-squares one.
AteResult computeAteOfPairs(const Eigen::Matrix3Xd& est, const Eigen::Matrix3Xd& gt,
                            bool with_scale, const std::optional<Alignment>& given = {});

/// ATE as evaluate_ate.py. Throws EvaluationError when fewer than 2 pairs associate.
AteResult computeAte(const std::vector<TimedPose>& gt, const std::vector<TimedPose>& est,
                     const TrajectoryEvalOptions& options);

/// RPE as evaluate_rpe.py --fixed_delta (all pairs, no random sub-sampling). `scale`
/// multiplies the estimated relative translations (the script's --scale). Zero pairs is a
/// valid result (stats NaN), e.g. for a sequence shorter than delta.
RpeResult computeRpe(const std::vector<TimedPose>& gt, const std::vector<TimedPose>& est,
                     const TrajectoryEvalOptions& options, double scale = 1.0);

/// ATE + RPE. With Sim(3) alignment the RPE uses the ATE scale. Inputs need not be sorted;
/// duplicate timestamps: the later entry wins (the scripts' dict semantics).
TrajectoryEvaluation evaluateTrajectories(const std::vector<TimedPose>& gt,
                                          const std::vector<TimedPose>& est,
                                          const TrajectoryEvalOptions& options);

/// {"ate": {...}, "rpe": {...}} on one line (keys as in `dynamap evaluate --json`).
std::string evaluationToJson(const TrajectoryEvaluation& evaluation);
/// {"pairs", "delta", "delta_unit", "trans_rmse_m", ...} of one RPE, on one line.
std::string rpeToJson(const RpeResult& rpe);
/// Human-readable table, several lines.
std::string evaluationToTable(const TrajectoryEvaluation& evaluation);

}  // namespace dynamap
