// ATE and RPE exactly as the TUM RGB-D benchmark scripts (evaluate_ate.py, evaluate_rpe.py)
// compute them; see /work/shared/data/groundtruth/GOLDEN.md for the reference numbers.
#include "trajectory_eval.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <utility>

#include <Eigen/SVD>

#include "json_io.hpp"
#include "tum_dataset.hpp"

namespace dynamap {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

/// Sorted by time, one pose per timestamp (a later duplicate replaces an earlier one).
std::vector<TimedPose> asTimeDict(const std::vector<TimedPose>& poses) {
  std::map<double, Eigen::Isometry3d> by_time;
  for (const TimedPose& p : poses) by_time.insert_or_assign(p.timestamp_s, p.T_W_C);
  std::vector<TimedPose> out;
  out.reserve(by_time.size());
  for (const auto& [t, T] : by_time) out.push_back({t, T});
  return out;
}

std::vector<double> stampsOf(const std::vector<TimedPose>& poses) {
  std::vector<double> stamps;
  stamps.reserve(poses.size());
  for (const TimedPose& p : poses) stamps.push_back(p.timestamp_s);
  return stamps;
}

double median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = values.size();
  std::sort(values.begin(), values.end());
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

/// evaluate_rpe.py find_closest_index: bisection that remembers the closest element visited.
std::size_t findClosestIndex(const std::vector<double>& sorted, double t) {
  std::size_t beginning = 0;
  std::size_t end = sorted.size();
  double difference = std::abs(sorted[0] - t);
  std::size_t best = 0;
  while (beginning < end) {
    const std::size_t middle = (end + beginning) / 2;
    if (std::abs(sorted[middle] - t) < difference) {
      difference = std::abs(sorted[middle] - t);
      best = middle;
    }
    if (t == sorted[middle]) return middle;
    if (sorted[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

/// evaluate_rpe.py: error44 = ominus(scale(ominus(E_j, E_i)), ominus(G_j, G_i)),
/// ominus(a, b) = inv(a) * b.
Eigen::Isometry3d relativeError(const Eigen::Isometry3d& E_i, const Eigen::Isometry3d& E_j,
                                const Eigen::Isometry3d& G_i, const Eigen::Isometry3d& G_j,
                                double scale) {
  Eigen::Isometry3d est_motion = E_j.inverse() * E_i;
  est_motion.translation() *= scale;
  const Eigen::Isometry3d gt_motion = G_j.inverse() * G_i;
  return est_motion.inverse() * gt_motion;
}

std::string formatRow(const char* name, double value, const char* unit) {
  char buffer[128];
  std::snprintf(buffer, sizeof(buffer), "  %-14s %12.6f%s%s\n", name, value, *unit ? " " : "",
                unit);
  return buffer;
}

Json rpeJsonOf(const RpeResult& r) {
  return Json{{"pairs", r.pairs},
              {"delta", r.delta},
              {"delta_unit", toString(r.unit)},
              {"trans_rmse_m", r.trans_m.rmse},
              {"trans_mean_m", r.trans_m.mean},
              {"trans_median_m", r.trans_m.median},
              {"rot_rmse_deg", r.rot_deg.rmse},
              {"rot_mean_deg", r.rot_deg.mean}};
}

}  // namespace

const char* toString(AlignmentKind kind) { return kind == AlignmentKind::kSim3 ? "sim3" : "se3"; }
const char* toString(RpeDeltaUnit unit) { return unit == RpeDeltaUnit::kFrames ? "f" : "s"; }

ErrorStats computeErrorStats(const std::vector<double>& errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.rmse = s.mean = s.median = s.std_dev = s.min = s.max = nan;
    return s;
  }
  const double n = static_cast<double>(errors.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std_dev = std::sqrt(var / n);
  s.median = median(errors);
  s.min = *std::min_element(errors.begin(), errors.end());
  s.max = *std::max_element(errors.begin(), errors.end());
  return s;
}

Alignment alignPositions(const Eigen::Matrix3Xd& est, const Eigen::Matrix3Xd& gt, bool with_scale) {
  const Eigen::Vector3d mean_est = est.rowwise().mean();
  const Eigen::Vector3d mean_gt = gt.rowwise().mean();
  const Eigen::Matrix3Xd est_c = est.colwise() - mean_est;
  const Eigen::Matrix3Xd gt_c = gt.colwise() - mean_gt;
  // Cross-covariance sum_k gt_k * est_k^T (evaluate_ate.py: svd(W.transpose())).
  const Eigen::Matrix3d W = gt_c * est_c.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(W, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;

  Alignment a;
  a.R = svd.matrixU() * S * svd.matrixV().transpose();
  if (with_scale) {
    const double est_var = est_c.squaredNorm();
    const double trace_ds = (svd.singularValues().asDiagonal() * S).trace();
    a.scale = est_var > 0.0 ? trace_ds / est_var : 1.0;
  }
  a.t = mean_gt - a.scale * a.R * mean_est;
  return a;
}

Alignment alignPoses(const std::vector<TimedPose>& gt_in, const std::vector<TimedPose>& est_in,
                     double max_time_diff_s, double rotation_weight_m2) {
  const std::vector<TimedPose> gt = asTimeDict(gt_in);
  const std::vector<TimedPose> est = asTimeDict(est_in);
  const auto matches = associateTimestamps(stampsOf(gt), stampsOf(est), max_time_diff_s);
  if (matches.size() < 2) throw EvaluationError("alignPoses: fewer than 2 associated pose pairs");
  Eigen::Vector3d mean_gt = Eigen::Vector3d::Zero(), mean_est = Eigen::Vector3d::Zero();
  for (const auto& [i_gt, i_est] : matches) {
    mean_gt += gt[i_gt].T_W_C.translation();
    mean_est += est[i_est].T_W_C.translation();
  }
  mean_gt /= static_cast<double>(matches.size());
  mean_est /= static_cast<double>(matches.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();  // maximise trace(R^T H)
  for (const auto& [i_gt, i_est] : matches) {
    H += (gt[i_gt].T_W_C.translation() - mean_gt) *
         (est[i_est].T_W_C.translation() - mean_est).transpose();
    H += rotation_weight_m2 * gt[i_gt].T_W_C.linear() * est[i_est].T_W_C.linear().transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) S(2, 2) = -1.0;
  Alignment a;
  a.R = svd.matrixU() * S * svd.matrixV().transpose();
  a.t = mean_gt - a.R * mean_est;
  return a;
}

AteResult computeAteOfPairs(const Eigen::Matrix3Xd& est, const Eigen::Matrix3Xd& gt,
                            bool with_scale, const std::optional<Alignment>& given) {
  AteResult r;
  r.with_scale = given ? given->scale != 1.0 : with_scale;
  r.alignment = given ? *given : alignPositions(est, gt, with_scale);
  r.alignment_given = given.has_value();
  r.pairs = static_cast<std::size_t>(est.cols());
  for (Eigen::Index k = 0; k < est.cols(); ++k) {
    const Eigen::Vector3d aligned = r.alignment.scale * r.alignment.R * est.col(k) + r.alignment.t;
    r.gt_positions_m.push_back(gt.col(k));
    r.est_aligned_m.push_back(aligned);
    r.errors_m.push_back((aligned - gt.col(k)).norm());
  }
  r.error_m = computeErrorStats(r.errors_m);
  return r;
}

AteResult computeAte(const std::vector<TimedPose>& gt_in, const std::vector<TimedPose>& est_in,
                     const TrajectoryEvalOptions& options) {
  const std::vector<TimedPose> gt = asTimeDict(gt_in);
  const std::vector<TimedPose> est = asTimeDict(est_in);
  const auto matches = associateTimestamps(stampsOf(gt), stampsOf(est), options.max_time_diff_s);
  if (matches.size() < 2) {
    char buffer[256];
    std::snprintf(buffer, sizeof(buffer),
                  "only %zu pose pair(s) of the estimate (%zu poses) and the ground truth "
                  "(%zu poses) lie within %.3f s of each other; need at least 2",
                  matches.size(), est.size(), gt.size(), options.max_time_diff_s);
    throw EvaluationError(buffer);
  }
  const auto n = static_cast<Eigen::Index>(matches.size());
  Eigen::Matrix3Xd est_xyz(3, n);
  Eigen::Matrix3Xd gt_xyz(3, n);
  std::vector<double> timestamps_s;
  for (Eigen::Index k = 0; k < n; ++k) {
    const auto& [i_gt, i_est] = matches[static_cast<std::size_t>(k)];
    gt_xyz.col(k) = gt[i_gt].T_W_C.translation();
    est_xyz.col(k) = est[i_est].T_W_C.translation();
    timestamps_s.push_back(gt[i_gt].timestamp_s);
  }
  AteResult r = computeAteOfPairs(est_xyz, gt_xyz, options.alignment == AlignmentKind::kSim3,
                                  options.given_alignment);
  r.timestamps_s = std::move(timestamps_s);
  return r;
}

RpeResult computeRpe(const std::vector<TimedPose>& gt_in, const std::vector<TimedPose>& est_in,
                     const TrajectoryEvalOptions& options, double scale) {
  const std::vector<TimedPose> gt = asTimeDict(gt_in);
  const std::vector<TimedPose> est = asTimeDict(est_in);
  RpeResult r;
  r.delta = options.rpe_delta;
  r.unit = options.rpe_unit;
  std::vector<double>& trans_errors = r.trans_errors_m;
  std::vector<double>& rot_errors = r.rot_errors_deg;  // radians until the end
  if (!gt.empty() && !est.empty()) {
    const std::vector<double> stamps_gt = stampsOf(gt);
    const std::vector<double> stamps_est = stampsOf(est);
    std::vector<double> index_est = stamps_est;
    if (options.rpe_unit == RpeDeltaUnit::kFrames) {
      for (std::size_t i = 0; i < index_est.size(); ++i) index_est[i] = static_cast<double>(i);
    }
    std::vector<double> gt_intervals;
    for (std::size_t i = 1; i < stamps_gt.size(); ++i) {
      gt_intervals.push_back(stamps_gt[i] - stamps_gt[i - 1]);
    }
    // NaN with < 2 ground-truth poses: like numpy, then nothing is rejected by the test below.
    const double gt_max_time_difference = 2.0 * median(gt_intervals);
    const std::size_t n = est.size();
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t j = findClosestIndex(index_est, index_est[i] + options.rpe_delta);
      if (j == n - 1) continue;  // the script drops pairs ending on the last pose
      const std::size_t g_i = findClosestIndex(stamps_gt, stamps_est[i]);
      const std::size_t g_j = findClosestIndex(stamps_gt, stamps_est[j]);
      if (std::abs(stamps_gt[g_i] - stamps_est[i]) > gt_max_time_difference ||
          std::abs(stamps_gt[g_j] - stamps_est[j]) > gt_max_time_difference) {
        continue;
      }
      const Eigen::Isometry3d error =
          relativeError(est[i].T_W_C, est[j].T_W_C, gt[g_i].T_W_C, gt[g_j].T_W_C, scale);
      r.timestamps_s.push_back(stamps_est[j]);
      trans_errors.push_back(error.translation().norm());
      const double c = std::clamp((error.linear().trace() - 1.0) / 2.0, -1.0, 1.0);
      rot_errors.push_back(std::acos(c));
    }
  }
  r.pairs = trans_errors.size();
  r.trans_m = computeErrorStats(trans_errors);
  r.rot_deg = computeErrorStats(rot_errors);
  for (double* v : {&r.rot_deg.rmse, &r.rot_deg.mean, &r.rot_deg.median, &r.rot_deg.std_dev,
                    &r.rot_deg.min, &r.rot_deg.max}) {
    *v *= kRadToDeg;
  }
  for (double& v : rot_errors) v *= kRadToDeg;
  return r;
}

TrajectoryEvaluation evaluateTrajectories(const std::vector<TimedPose>& gt,
                                          const std::vector<TimedPose>& est,
                                          const TrajectoryEvalOptions& options) {
  TrajectoryEvaluation evaluation;
  evaluation.ate = computeAte(gt, est, options);
  evaluation.rpe = computeRpe(gt, est, options, evaluation.ate.alignment.scale);
  return evaluation;
}

std::string evaluationToJson(const TrajectoryEvaluation& evaluation) {
  const AteResult& a = evaluation.ate;
  Json ate = {{"pairs", a.pairs},           {"rmse_m", a.error_m.rmse},
              {"mean_m", a.error_m.mean},   {"median_m", a.error_m.median},
              {"std_m", a.error_m.std_dev}, {"min_m", a.error_m.min},
              {"max_m", a.error_m.max}};
  if (a.with_scale) ate["scale"] = a.alignment.scale;
  if (a.alignment_given) ate["alignment"] = "given";
  return dumpJson(Json{{"ate", ate}, {"rpe", rpeJsonOf(evaluation.rpe)}});
}

std::string rpeToJson(const RpeResult& rpe) { return dumpJson(rpeJsonOf(rpe)); }

std::string evaluationToTable(const TrajectoryEvaluation& evaluation) {
  const AteResult& a = evaluation.ate;
  const RpeResult& r = evaluation.rpe;
  const std::string kind = a.alignment_given ? "given" : (a.with_scale ? "sim3" : "se3");
  std::string out = "ATE (" + kind + " alignment, " +
                    std::to_string(a.pairs) + " pairs)\n";
  out += formatRow("rmse", a.error_m.rmse, "m");
  out += formatRow("mean", a.error_m.mean, "m");
  out += formatRow("median", a.error_m.median, "m");
  out += formatRow("std", a.error_m.std_dev, "m");
  out += formatRow("min", a.error_m.min, "m");
  out += formatRow("max", a.error_m.max, "m");
  if (a.with_scale) out += formatRow("scale", a.alignment.scale, "");
  char header[128];
  std::snprintf(header, sizeof(header), "RPE (delta %g %s, %zu pairs)\n", r.delta, toString(r.unit),
                r.pairs);
  out += header;
  out += formatRow("trans rmse", r.trans_m.rmse, "m");
  out += formatRow("trans mean", r.trans_m.mean, "m");
  out += formatRow("trans median", r.trans_m.median, "m");
  out += formatRow("rot rmse", r.rot_deg.rmse, "deg");
  out += formatRow("rot mean", r.rot_deg.mean, "deg");
  return out;
}

}  // namespace dynamap
