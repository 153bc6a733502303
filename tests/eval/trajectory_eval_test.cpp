#include "trajectory_eval.hpp"

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_paths.hpp"

namespace dynamap {
namespace {

namespace fs = std::filesystem;

/// One row of the table in GOLDEN.md (numbers as printed there, 6 decimals).
struct GoldenRow {
  std::string gt_file, est_file;
  std::size_t ate_pairs = 0;
  double ate_rmse, ate_mean, ate_median, ate_std, ate_max;
  std::size_t rpe_pairs = 0;
  double rpe_trans_rmse, rpe_rot_rmse;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(' ');
  const auto e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

/// Parses the rows of GOLDEN.md's table ("| gt | est | pairs | 0.013473 m | ...").
std::vector<GoldenRow> readGoldenRows(const fs::path& path) {
  std::ifstream in(path);
  std::vector<GoldenRow> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("| freiburg", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    std::string cell;
    while (std::getline(ss, cell, '|')) cells.push_back(trim(cell));
    if (cells.size() < 11) continue;
    GoldenRow r;
    r.gt_file = cells[0];
    r.est_file = cells[1];
    r.ate_pairs = std::stoul(cells[2]);
    r.ate_rmse = std::stod(cells[3]);
    r.ate_mean = std::stod(cells[4]);
    r.ate_median = std::stod(cells[5]);
    r.ate_std = std::stod(cells[6]);
    r.ate_max = std::stod(cells[7]);
    r.rpe_pairs = std::stoul(cells[8]);
    r.rpe_trans_rmse = std::stod(cells[9]);
    r.rpe_rot_rmse = std::stod(cells[10]);
    rows.push_back(r);
  }
  return rows;
}

TEST(TrajectoryEvalGolden, ReproducesBothRowsOfGoldenMd) {
  DYNAMAP_REQUIRE_SHARED_DATA();
  const fs::path dir = test::sharedData() / "groundtruth";
  const std::vector<GoldenRow> rows = readGoldenRows(dir / "GOLDEN.md");
  ASSERT_EQ(rows.size(), 2u) << "GOLDEN.md table not found or changed";
  constexpr double kTol = 5e-7;  // half a unit of the 6th printed decimal
  for (const GoldenRow& g : rows) {
    SCOPED_TRACE(g.est_file);
    const auto gt = readTrajectory((dir / g.gt_file).string());
    const auto est = readTrajectory((dir / g.est_file).string());
    const TrajectoryEvaluation e = evaluateTrajectories(gt, est, TrajectoryEvalOptions{});
    EXPECT_EQ(e.ate.pairs, g.ate_pairs);
    EXPECT_NEAR(e.ate.error_m.rmse, g.ate_rmse, kTol);
    EXPECT_NEAR(e.ate.error_m.mean, g.ate_mean, kTol);
    EXPECT_NEAR(e.ate.error_m.median, g.ate_median, kTol);
    EXPECT_NEAR(e.ate.error_m.std_dev, g.ate_std, kTol);
    EXPECT_NEAR(e.ate.error_m.max, g.ate_max, kTol);
    EXPECT_EQ(e.rpe.pairs, g.rpe_pairs);
    EXPECT_NEAR(e.rpe.trans_m.rmse, g.rpe_trans_rmse, kTol);
    EXPECT_NEAR(e.rpe.rot_deg.rmse, g.rpe_rot_rmse, kTol);
  }
}

/// A smooth synthetic trajectory (a wobbly loop), 30 Hz, `n` poses, seeded.
std::vector<TimedPose> syntheticTrajectory(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, 1.0);
  const double p0 = phase(rng), p1 = phase(rng);
  std::vector<TimedPose> poses;
  for (int k = 0; k < n; ++k) {
    const double s = 0.02 * k;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() =
        Eigen::Vector3d(2.0 * std::cos(s + p0), 1.5 * std::sin(s), 0.3 * std::sin(3 * s + p1));
    T.linear() = Eigen::AngleAxisd(s, Eigen::Vector3d::UnitZ()).matrix() *
                 Eigen::AngleAxisd(0.2 * std::sin(2 * s), Eigen::Vector3d::UnitX()).matrix();
    poses.push_back({100.0 + k / 30.0, T});
  }
  return poses;
}

Eigen::Isometry3d knownTransform() {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  X.translation() = Eigen::Vector3d(0.5, -1.2, 2.0);
  return X;
}

TEST(TrajectoryEval, RecoversKnownRigidTransformUnderNoise) {
  const auto gt = syntheticTrajectory(600, 1);
  const Eigen::Isometry3d X = knownTransform();  // est frame -> gt frame
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<TimedPose> est;
  for (const TimedPose& p : gt) {
    Eigen::Isometry3d T = X.inverse() * p.T_W_C;
    T.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    est.push_back({p.timestamp_s + 0.003, T});  // small clock offset, inside 0.02 s
  }
  const AteResult ate = computeAte(gt, est, TrajectoryEvalOptions{});
  EXPECT_EQ(ate.pairs, 600u);
  const double angle_err = Eigen::AngleAxisd(ate.alignment.R.transpose() * X.linear()).angle();
  EXPECT_LT(angle_err, 2e-3);
  EXPECT_LT((ate.alignment.t - X.translation()).norm(), 5e-3);
  EXPECT_DOUBLE_EQ(ate.alignment.scale, 1.0);
  // RMSE of 3-D Gaussian noise (sigma 2 mm) is about sigma * sqrt(3) = 3.46 mm.
  EXPECT_NEAR(ate.error_m.rmse, 0.002 * std::sqrt(3.0), 0.0004);
  // Noise-free: exact.
  std::vector<TimedPose> exact;
  for (const TimedPose& p : gt) exact.push_back({p.timestamp_s, X.inverse() * p.T_W_C});
  EXPECT_LT(computeAte(gt, exact, TrajectoryEvalOptions{}).error_m.max, 1e-9);
}

// A straight path (x axis, 40 cm) with 1 mm position noise: the positions leave the roll about
// the path free, the orientations fix it. alignPoses recovers a 10 degree roll; the ATE's
// position-only alignment need not.
TEST(TrajectoryEval, PoseAlignmentFixesRollAboutAStraightPath) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();  // est frame -> gt frame
  X.rotate(Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
  X.translation() = Eigen::Vector3d(0.3, -0.2, 0.1);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.001);
  std::vector<TimedPose> gt, est;
  for (int k = 0; k < 100; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.rotate(Eigen::AngleAxisd(0.3 * std::sin(0.1 * k), Eigen::Vector3d::UnitY()));
    T.translation() = Eigen::Vector3d(0.004 * k, 0.0, 0.0);
    gt.push_back({0.1 * k, T});
    Eigen::Isometry3d E = X.inverse() * T;
    E.translation() += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    est.push_back({0.1 * k, E});
  }
  const Alignment a = alignPoses(gt, est, 0.02);
  EXPECT_LT(Eigen::AngleAxisd(a.R.transpose() * X.linear()).angle(), 0.2 * M_PI / 180.0);
  EXPECT_LT((a.t - X.translation()).norm(), 0.005);
  EXPECT_DOUBLE_EQ(a.scale, 1.0);
  EXPECT_THROW(alignPoses(gt, {est.front()}, 0.02), EvaluationError);
}

TEST(TrajectoryEval, Sim3RecoversKnownScale) {
  const auto gt = syntheticTrajectory(400, 2);
  const Eigen::Isometry3d X = knownTransform();
  const double scale = 2.5;  // gt = scale * (R * est) + t
  std::vector<TimedPose> est;
  for (const TimedPose& p : gt) {
    Eigen::Isometry3d T = X.inverse() * p.T_W_C;
    T.translation() /= scale;
    est.push_back({p.timestamp_s, T});
  }
  TrajectoryEvalOptions options;
  options.alignment = AlignmentKind::kSim3;
  const TrajectoryEvaluation e = evaluateTrajectories(gt, est, options);
  EXPECT_NEAR(e.ate.alignment.scale, scale, 1e-9);
  EXPECT_LT(e.ate.error_m.max, 1e-9);
  EXPECT_LT(e.rpe.trans_m.max, 1e-9);  // RPE uses the ATE scale
  EXPECT_NE(evaluationToJson(e).find("\"scale\":2."), std::string::npos) << evaluationToJson(e);
  // Rigid alignment cannot explain the scale.
  EXPECT_GT(computeAte(gt, est, TrajectoryEvalOptions{}).error_m.rmse, 0.1);
}

TEST(TrajectoryEval, ReflectionIsNotAcceptedAsRotation) {
  // Mirror image of a non-planar trajectory: the best proper rotation leaves an error.
  const auto gt = syntheticTrajectory(300, 3);
  std::vector<TimedPose> est;
  for (TimedPose p : gt) {
    p.T_W_C.translation().z() *= -1.0;
    est.push_back(p);
  }
  const AteResult ate = computeAte(gt, est, TrajectoryEvalOptions{});
  EXPECT_NEAR(ate.alignment.R.determinant(), 1.0, 1e-9);
  EXPECT_GT(ate.error_m.rmse, 0.01);
}

TEST(TrajectoryEval, RpeOfIdenticalTrajectoriesIsZero) {
  const auto gt = syntheticTrajectory(300, 4);
  const RpeResult r = computeRpe(gt, gt, TrajectoryEvalOptions{});
  // 30 Hz, 10 s, delta 1 s: pair (i, i+30) for i + 30 < 299; pairs ending on the last pose
  // are dropped as in evaluate_rpe.py -> 269 pairs.
  EXPECT_EQ(r.pairs, 269u);
  EXPECT_LT(r.trans_m.max, 1e-12);
  EXPECT_LT(r.rot_deg.max, 1e-5);
  TrajectoryEvalOptions frames;
  frames.rpe_unit = RpeDeltaUnit::kFrames;
  frames.rpe_delta = 30;
  EXPECT_EQ(computeRpe(gt, gt, frames).pairs, 269u);
}

// A straight line at 30 frames/s, 0.10 m/s in the ground truth and 0.11 m/s in the estimate,
// no rotation: 0.01 m of error per second.
void driftingLine(int frames, std::vector<TimedPose>* gt, std::vector<TimedPose>* est) {
  for (int k = 0; k < frames; ++k) {
    const double t = k / 30.0;
    Eigen::Isometry3d G = Eigen::Isometry3d::Identity(), E = G;
    G.translation().x() = 0.10 * t;
    E.translation().x() = 0.11 * t;
    gt->push_back({t, G});
    est->push_back({t, E});
  }
}

TEST(TrajectoryEval, RpeMeasuresKnownDrift) {
  // Straight line at 0.10 m/s (gt) vs 0.11 m/s (est), no rotation: 0.01 m error per second.
  std::vector<TimedPose> gt, est;
  driftingLine(150, &gt, &est);
  const RpeResult r = computeRpe(gt, est, TrajectoryEvalOptions{});
  EXPECT_GT(r.pairs, 100u);
  EXPECT_NEAR(r.trans_m.rmse, 0.01, 1e-9);
  EXPECT_NEAR(r.trans_m.mean, 0.01, 1e-9);
  EXPECT_LT(r.rot_deg.rmse, 1e-5);
}

TEST(TrajectoryEval, RpeKeepsEveryPairAndItsStatsComeFromThem) {
  // Straight line at 0.10 m/s (gt) vs 0.11 m/s (est), one frame apart: 1/3 mm per pair.
  std::vector<TimedPose> gt, est;
  driftingLine(60, &gt, &est);
  TrajectoryEvalOptions frames;
  frames.rpe_unit = RpeDeltaUnit::kFrames;
  const RpeResult r = computeRpe(gt, est, frames);
  ASSERT_EQ(r.timestamps_s.size(), r.pairs);
  ASSERT_EQ(r.trans_errors_m.size(), r.pairs);
  ASSERT_EQ(r.rot_errors_deg.size(), r.pairs);
  EXPECT_NEAR(r.timestamps_s.front(), 1.0 / 30.0, 1e-12);  // the later pose of the first pair
  for (std::size_t i = 0; i < r.pairs; ++i) {
    EXPECT_NEAR(r.trans_errors_m[i], 0.01 / 30.0, 1e-9);
    EXPECT_LT(r.rot_errors_deg[i], 1e-5);
  }
  EXPECT_NEAR(computeErrorStats(r.trans_errors_m).rmse, r.trans_m.rmse, 1e-12);
}

TEST(TrajectoryEval, NoOverlapIsAnErrorAndShortRunHasNoRpePairs) {
  const auto gt = syntheticTrajectory(100, 5);
  std::vector<TimedPose> est = gt;
  for (TimedPose& p : est) p.timestamp_s += 1000.0;
  try {
    computeAte(gt, est, TrajectoryEvalOptions{});
    FAIL() << "expected EvaluationError";
  } catch (const EvaluationError& e) {
    EXPECT_NE(std::string(e.what()).find("only 0 pose pair"), std::string::npos) << e.what();
  }
  const std::vector<TimedPose> short_est(gt.begin(), gt.begin() + 10);  // 0.3 s < delta
  const TrajectoryEvaluation e = evaluateTrajectories(gt, short_est, TrajectoryEvalOptions{});
  EXPECT_EQ(e.ate.pairs, 10u);
  EXPECT_EQ(e.rpe.pairs, 0u);
  EXPECT_TRUE(std::isnan(e.rpe.trans_m.rmse));
  EXPECT_NE(evaluationToJson(e).find("\"trans_rmse_m\":null"), std::string::npos);
}

TEST(ErrorStats, NumpySemantics) {
  const ErrorStats odd = computeErrorStats({3.0, 1.0, 2.0});
  EXPECT_DOUBLE_EQ(odd.median, 2.0);
  const ErrorStats even = computeErrorStats({4.0, 1.0, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(even.median, 2.5);
  EXPECT_DOUBLE_EQ(even.mean, 2.5);
  EXPECT_DOUBLE_EQ(even.std_dev, std::sqrt(1.25));  // population, not sample
  EXPECT_DOUBLE_EQ(even.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(even.min, 1.0);
  EXPECT_DOUBLE_EQ(even.max, 4.0);
}

TEST(TrajectoryEval, JsonAndTableNameEveryMetric) {
  const auto gt = syntheticTrajectory(200, 6);
  const TrajectoryEvaluation e = evaluateTrajectories(gt, gt, TrajectoryEvalOptions{});
  const std::string json = evaluationToJson(e);
  for (const char* key :
       {"\"ate\":{", "\"pairs\":200", "\"rmse_m\":", "\"mean_m\":", "\"median_m\":", "\"std_m\":",
        "\"min_m\":", "\"max_m\":", "\"rpe\":{", "\"delta\":1", "\"delta_unit\":\"s\"",
        "\"trans_rmse_m\":", "\"trans_mean_m\":", "\"rot_rmse_deg\":", "\"rot_mean_deg\":"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " not in " << json;
  }
  EXPECT_EQ(json.find("scale"), std::string::npos);
  const std::string table = evaluationToTable(e);
  EXPECT_NE(table.find("ATE (se3 alignment, 200 pairs)"), std::string::npos) << table;
  EXPECT_NE(table.find("rot rmse"), std::string::npos) << table;
}

}  // namespace
}  // namespace dynamap
