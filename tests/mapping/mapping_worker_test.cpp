#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#ifdef __linux__
#include <sys/resource.h>
#include <unistd.h>
#endif

#include "mapping_test_utils.hpp"

namespace dynamap::test {
namespace {

// Records what the worker hands it; integrate() blocks until released.
struct FakeLog {
  std::mutex mutex;
  std::condition_variable cv;
  bool released = false;
  std::vector<std::uint64_t> integrated;
  std::vector<std::size_t> points;
  std::map<std::uint64_t, Eigen::Isometry3d> poses;
  int resets = 0;
  std::vector<std::pair<std::uint64_t, Eigen::Isometry3d>> taken_out;  ///< id, pose it left at
};

class FakeBackend final : public MapBackend {
 public:
  FakeBackend(FakeLog* log, PoseUpdateMode mode, bool fuses = false, bool deintegrates = false,
              double cell_m = 0.0)
      : log_(log), mode_(mode), fuses_(fuses), deintegrates_(deintegrates), cell_m_(cell_m) {}
  void integrate(const KeyframeView& view) override {
    std::unique_lock<std::mutex> lock(log_->mutex);
    log_->cv.wait(lock, [&] { return log_->released; });
    log_->integrated.push_back(view.id);
    log_->points.push_back(view.points_C->size());
    log_->poses[view.id] = view.T_W_C;
  }
  void updatePose(std::uint64_t id, const Eigen::Isometry3d& T_W_C) override {
    std::lock_guard<std::mutex> lock(log_->mutex);
    log_->poses[id] = T_W_C;
  }
  PoseUpdateMode poseUpdateMode() const override { return mode_; }
  void reset() override { ++log_->resets; }
  void exportMap(const std::string&) override {}
  MapStats stats() const override { return {}; }
  bool fusesViews() const override { return fuses_; }
  bool canDeintegrate() const override { return deintegrates_; }
  double cellSizeM() const override { return cell_m_; }
  void deintegrate(const KeyframeView& view) override {
    std::lock_guard<std::mutex> lock(log_->mutex);
    log_->taken_out.emplace_back(view.id, view.T_W_C);
  }

 private:
  FakeLog* log_;
  PoseUpdateMode mode_;
  bool fuses_;
  bool deintegrates_;
  double cell_m_;
};

KeyframePacketPtr packet(std::uint64_t id) {
  const SyntheticFrame f = SyntheticScene().render(static_cast<int>(id % 6), 6);
  auto kf = std::make_shared<KeyframePacket>();
  kf->id = id;
  kf->T_W_C = f.T_W_C;
  kf->bgr = f.bgr;
  kf->depth_m = f.depth_m;
  kf->dynamic_mask = f.mask;
  return kf;
}

/// For the tests that count integrations, which assume the visibility pass removes nothing:
/// beside the moving box its beside-a-mover votes take a few room voxels that only one of these
/// few keyframes saw (and the worker would rebuild).
StaticPointsOptions countingOptions() {
  StaticPointsOptions o;
  o.visibility.mask_near_px = 0;
  return o;
}

TEST(MappingWorker, BoundedQueueDropsOnTryPushAndDrainsOnFinish) {
  FakeLog log;
  TimingRecorder timings;
  StaticPointsOptions options = countingOptions();
  options.free_space.enabled = false;  // integrate on arrival (no neighbour window)
  options.window_after_s = 0.0;        // ... nor judgement window
  options.window_batch_s = 0.0;
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), options, 1, &timings);
  worker.push(packet(1));  // taken by the worker thread, which blocks in integrate()
  // Wait until the worker took it, then fill the single queue slot.
  for (int i = 0; i < 2000 && !worker.tryPush(packet(2)); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_FALSE(worker.tryPush(packet(3)));
  EXPECT_GE(worker.droppedKeyframes(), 1u);
  {
    std::lock_guard<std::mutex> lock(log.mutex);
    log.released = true;
  }
  log.cv.notify_all();
  worker.finish();
  EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{1, 2}));
  EXPECT_EQ(timings.stats("mapping_integrate").count, 2u);
  ASSERT_EQ(log.points.size(), 2u);
  EXPECT_GT(log.points[0], 1000u);
}

// A backend that drains after the final poses keeps a short queue: what is queued at finish()
// goes in after the final bundle adjustment, so the queue bounds the finish. One that drains
// beside it keeps the whole capacity (bursts of the mapper's work cost the tracker nothing).
TEST(MappingWorker, ABackendThatDrainsAfterTheFinalPosesKeepsAShortQueue) {
  for (const PoseUpdateMode mode : {PoseUpdateMode::kReintegrate, PoseUpdateMode::kInPlace}) {
    FakeLog log;  // integrate() blocks until released: the worker holds the first keyframe
    StaticPointsOptions options = countingOptions();
    options.free_space.enabled = false;  // integrate on arrival (no neighbour window)
    options.window_after_s = 0.0;        // ... nor judgement window
    options.window_batch_s = 0.0;
    MappingWorker worker(std::make_unique<FakeBackend>(&log, mode), SyntheticScene::camera(),
                         options, 16, nullptr);
    std::vector<KeyframePacketPtr> packets;
    for (std::uint64_t id = 0; id < 12; ++id) packets.push_back(packet(id));
    std::atomic<int> pushed{0};
    std::thread tracker([&] {
      for (const auto& kf : packets) {
        worker.push(kf);
        ++pushed;
      }
    });
    // Until the pushes stop (all 12, or blocked at the short queue), then a while longer.
    const int short_limit = 1 + static_cast<int>(MappingWorker::kAfterFinalPosesQueue);
    for (int i = 0; i < 5000 && pushed.load() < 12 && pushed.load() < short_limit; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const int before_release = pushed.load();
    {
      std::lock_guard<std::mutex> lock(log.mutex);
      log.released = true;
    }
    log.cv.notify_all();
    tracker.join();
    worker.finish();
    EXPECT_EQ(log.integrated.size(), 12u);
    if (mode == PoseUpdateMode::kReintegrate) {
      EXPECT_TRUE(worker.drainsAfterFinalPoses());
      EXPECT_LE(before_release, short_limit);  // the one the worker holds and the queue's 4
    } else {
      EXPECT_FALSE(worker.drainsAfterFinalPoses());
      EXPECT_EQ(before_release, 12);
    }
  }
}

#ifdef __linux__
/// The nice value of each of this process's threads (/proc/self/task/<tid>/stat, field 19).
std::vector<int> threadNiceValues() {
  std::vector<int> out;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream in(task.path() / "stat");
    std::string stat((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream fields(stat.substr(stat.rfind(')') + 2));  // after "pid (name) "
    std::string field;
    for (int i = 3; i <= 19 && fields >> field; ++i) {
    }
    out.push_back(std::stoi(field));
  }
  return out;
}

/// Whether a thread of this process may take nice value `value` (raising is always allowed,
/// lowering needs CAP_SYS_NICE).
bool threadMayTakeNice(int value) {
  bool ok = false;
  std::thread probe(
      [&] { ok = setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), value) == 0; });
  probe.join();
  return ok;
}

// The mapping thread alone takes the nice value it is given; the caller's thread keeps its own.
// The test may itself run niced (scripts/sanitize.sh runs ctest under nice 19): the value asked
// for is 7 away from the caller's own.
TEST(MappingWorker, ThreadNiceAppliesToTheMappingThreadOnly) {
  FakeLog log;
  TimingRecorder timings;
  const int own = getpriority(PRIO_PROCESS, static_cast<id_t>(gettid()));
  const int seven = own + 7 <= 19 ? own + 7 : own - 7;
  if (!threadMayTakeNice(seven)) GTEST_SKIP() << "this process may not take nice " << seven;
  const std::vector<int> start = threadNiceValues();
  const int before = static_cast<int>(std::count(start.begin(), start.end(), seven));
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), countingOptions(), 2, &timings, seven);
  int with_seven = 0;
  for (int i = 0; i < 2000 && with_seven <= before; ++i) {  // the thread sets it when it starts
    const std::vector<int> nice = threadNiceValues();
    with_seven = static_cast<int>(std::count(nice.begin(), nice.end(), seven));
    if (with_seven <= before) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(with_seven, before + 1);
  EXPECT_EQ(getpriority(PRIO_PROCESS, static_cast<id_t>(gettid())), own);
  {
    std::lock_guard<std::mutex> lock(log.mutex);
    log.released = true;
  }
  log.cv.notify_all();
  worker.finish();
}
#endif

TEST(MappingWorker, FreeSpaceWindowIntegratesEveryKeyframeInOrderByFinish) {
  FakeLog log;
  log.released = true;
  TimingRecorder timings;
  StaticPointsOptions options;
  options.free_space.enabled = true;
  options.free_space.neighbours = 2;
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), options, 8, &timings);
  for (std::uint64_t id = 1; id <= 5; ++id) worker.push(packet(id));
  worker.finish();  // the last two wait for later neighbours until the flush
  EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(timings.stats("mapping_free_space").count, 5u);
  ASSERT_EQ(log.points.size(), 5u);
  // A static synthetic scene: the check removes (almost) nothing.
  for (const std::size_t n : log.points) EXPECT_GT(n, 1000u);
}

TEST(MappingWorker, ForwardsPoseUpdatesIncludingEarlyOnes) {
  FakeLog log;
  log.released = true;
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), StaticPointsOptions{}, 4, nullptr);
  Eigen::Isometry3d moved = Eigen::Isometry3d::Identity();
  moved.translation() << 1, 2, 3;
  worker.applyPoseUpdates({{7, moved}});  // before keyframe 7 exists
  worker.push(packet(7));
  worker.finish();
  ASSERT_EQ(log.poses.count(7), 1u);
  EXPECT_TRUE(log.poses.at(7).isApprox(moved));
  EXPECT_EQ(log.resets, 0);
}

TEST(MappingWorker, RebuildsVolumetricBackendsOnlyWhenPosesMoved) {
  for (const double dx : {0.001, 0.05}) {
    FakeLog log;
    log.released = true;
    MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate),
                         SyntheticScene::camera(), countingOptions(), 4, nullptr);
    std::vector<PoseUpdate> updates;
    for (std::uint64_t id = 0; id < 3; ++id) {
      const auto kf = packet(id);
      worker.push(kf);
      updates.push_back({id, Eigen::Translation3d(dx, 0, 0) * kf->T_W_C});
    }
    worker.drain();  // integrated (as System::finish(): then the final poses come)
    worker.applyPoseUpdates(updates);
    worker.finish();
    const bool rebuilt = dx > MappingWorker::kReintegrateTranslationM;
    EXPECT_EQ(log.resets, rebuilt ? 1 : 0) << dx;
    EXPECT_EQ(log.integrated.size(), rebuilt ? 6u : 3u) << dx;
    EXPECT_EQ(worker.reintegratedKeyframes(), rebuilt ? 3u : 0u);
    if (rebuilt) {
      EXPECT_TRUE(log.poses.at(2).isApprox(updates[2].T_W_C));
      EXPECT_EQ(log.points[3], log.points[0]);  // same static points from the stored depth
    }
  }
}

// A backend that can take keyframes out gets only the moved ones out (at the pose they went in
// with) and in again (at their final pose) while fewer than half moved; else the whole rebuild.
TEST(MappingWorker, MovesOnlyTheMovedKeyframesOfABackendThatCanTakeThemOut) {
  for (const int moved : {1, 2}) {  // of 4: out and in again / rebuild
    FakeLog log;
    log.released = true;
    MappingWorker worker(
        std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate, false, true),
        SyntheticScene::camera(), countingOptions(), 4, nullptr);
    std::vector<PoseUpdate> updates;
    std::vector<Eigen::Isometry3d> first;
    for (std::uint64_t id = 0; id < 4; ++id) {
      const auto kf = packet(id);
      worker.push(kf);
      first.push_back(kf->T_W_C);
      const double dx = static_cast<int>(id) < moved ? 0.05 : 0.001;
      updates.push_back({id, Eigen::Translation3d(dx, 0, 0) * kf->T_W_C});
    }
    worker.drain();
    worker.applyPoseUpdates(updates);
    worker.finish();
    if (moved == 1) {
      EXPECT_EQ(log.resets, 0);
      ASSERT_EQ(log.taken_out.size(), 1u);
      EXPECT_EQ(log.taken_out[0].first, 0u);
      EXPECT_TRUE(log.taken_out[0].second.isApprox(first[0]));
      EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2, 3, 0}));
      EXPECT_EQ(log.points[4], log.points[0]);  // the same static points, from the stored depth
      EXPECT_EQ(worker.reintegratedKeyframes(), 1u);
    } else {
      EXPECT_EQ(log.resets, 1);
      EXPECT_TRUE(log.taken_out.empty());
      EXPECT_EQ(log.integrated.size(), 8u);
      EXPECT_EQ(worker.reintegratedKeyframes(), 4u);
    }
    EXPECT_TRUE(log.poses.at(0).isApprox(updates[0].T_W_C));
  }
}

// A keyframe moved by less than half a cell of the backend's map (5 cm cells: 2 cm) stays where
// it went in; beyond (3 cm), it is taken out and put in again. Cells of 2 cm or none: 1 cm.
TEST(MappingWorker, AKeyframeMovedByLessThanHalfACellStays) {
  for (const double cell : {0.0, 0.02, 0.05}) {
    for (const double dx : {0.015, 0.02, 0.03}) {
      FakeLog log;
      log.released = true;
      MappingWorker worker(
          std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate, false, true, cell),
          SyntheticScene::camera(), countingOptions(), 4, nullptr);
      std::vector<PoseUpdate> updates;
      for (std::uint64_t id = 0; id < 3; ++id) {
        const auto kf = packet(id);
        worker.push(kf);
        const double shift = id == 0 ? dx : 0.0;
        updates.push_back({id, Eigen::Translation3d(shift, 0, 0) * kf->T_W_C});
      }
      worker.drain();
      worker.applyPoseUpdates(updates);
      worker.finish();
      const bool moves = dx > std::max(MappingWorker::kReintegrateTranslationM, cell / 2);
      EXPECT_EQ(log.taken_out.size(), moves ? 1u : 0u) << cell << " " << dx;
      EXPECT_EQ(log.resets, 0);
    }
  }
}

// Final poses published before drain() (System::finish() for a backend that re-integrates,
// drainsAfterFinalPoses()) reach the keyframes still waiting in the window before they go in:
// each goes in once, at its final pose; none is taken out again and there is no rebuild.
TEST(MappingWorker, FinalPosesBeforeTheDrainPlaceTheLastKeyframesOnce) {
  FakeLog log;
  log.released = true;
  MappingWorker worker(
      std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate, false, true),
      SyntheticScene::camera(), countingOptions(), 4, nullptr);
  EXPECT_TRUE(worker.drainsAfterFinalPoses());
  std::vector<PoseUpdate> updates;
  for (std::uint64_t id = 0; id < 3; ++id) {
    const auto kf = packet(id);
    worker.push(kf);
    updates.push_back({id, Eigen::Translation3d(0.05, 0, 0) * kf->T_W_C});
  }
  worker.applyPoseUpdates(updates);
  worker.drain();
  worker.finish();
  EXPECT_EQ(log.resets, 0);
  EXPECT_TRUE(log.taken_out.empty());
  EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2}));
  for (const auto& u : updates) EXPECT_TRUE(log.poses.at(u.keyframe_id).isApprox(u.T_W_C));
  EXPECT_EQ(worker.reintegratedKeyframes(), 0u);
}

// The final pass (mapping.visibility_final_pass, the offline extra): the backend gets each
// keyframe exactly once, in finish(), with its final pose, and never a reset. Online (the
// default) each keyframe is integrated when judged, here in drain(); the final poses then cost
// a volumetric backend a second integration of every keyframe after a reset. The points are the
// same either way (from the stored static depth).
TEST(MappingWorker, TheFinalPassIntegratesEachKeyframeOnceWithItsFinalPose) {
  std::vector<std::size_t> points[2];  // [online, final pass]: points per keyframe
  for (const bool final_pass : {true, false}) {
    FakeLog log;
    log.released = true;
    TimingRecorder timings;
    StaticPointsOptions options = countingOptions();
    options.visibility_final_pass = final_pass;
    MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate),
                         SyntheticScene::camera(), options, 4, &timings);
    std::vector<PoseUpdate> updates;
    for (std::uint64_t id = 0; id < 4; ++id) {
      const auto kf = packet(id);
      worker.push(kf);
      updates.push_back({id, Eigen::Translation3d(0.05, 0, 0) * kf->T_W_C});
    }
    worker.drain();
    worker.applyPoseUpdates(updates);
    worker.finish();
    if (final_pass) {
      EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2, 3}));
      EXPECT_EQ(log.resets, 0);
    } else {
      EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2, 3, 0, 1, 2, 3}));
      EXPECT_EQ(log.resets, 1);
    }
    EXPECT_EQ(timings.stats("mapping_keyframe").count, 4u);
    // One timed backend integration per keyframe either way (final pass: those of finish()).
    EXPECT_EQ(timings.stats("mapping_integrate").count, 4u);
    for (const auto& u : updates) EXPECT_TRUE(log.poses.at(u.keyframe_id).isApprox(u.T_W_C));
    ASSERT_GE(log.points.size(), 4u);
    points[final_pass ? 1 : 0].assign(log.points.end() - 4, log.points.end());
    if (!final_pass) {
      EXPECT_EQ(points[0], std::vector<std::size_t>(log.points.begin(), log.points.begin() + 4));
    }
  }
  EXPECT_EQ(points[1], points[0]);
  EXPECT_GT(points[1].front(), 1000u);
}

/// countingOptions() with the judgement window only: a keyframe 0.25 s later, no batching.
StaticPointsOptions onlineWindowOptions() {
  StaticPointsOptions options = countingOptions();
  options.free_space.enabled = false;
  options.window_after_s = 0.25;
  options.window_batch_s = 0.0;
  return options;
}

// Online, a keyframe goes to the backend once a keyframe window_after_s later has arrived,
// judged against those within window_before_s before it; a kInPlace backend gets the pose
// updates of the integrated ones, and the worker keeps no image of theirs.
TEST(MappingWorker, OnlineKeyframesReachTheBackendOnceTheirWindowIsThere) {
  FakeLog log;
  log.released = true;
  StaticPointsOptions options = onlineWindowOptions();
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), options, 4, nullptr);
  for (std::uint64_t id = 0; id < 6; ++id) {
    auto kf = std::make_shared<KeyframePacket>(*packet(id));
    kf->timestamp_s = 0.1 * static_cast<double>(id);
    worker.push(kf);
  }
  worker.waitIdle();
  {
    std::lock_guard<std::mutex> lock(log.mutex);  // 0.5 s: keyframes at 0.0, 0.1, 0.2
    EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2}));
  }
  const Eigen::Isometry3d moved = Eigen::Translation3d(0.0, 0.02, 0.0) * packet(1)->T_W_C;
  worker.applyPoseUpdates({{1, moved}});
  worker.finish();
  EXPECT_EQ(log.integrated, (std::vector<std::uint64_t>{0, 1, 2, 3, 4, 5}));
  EXPECT_TRUE(log.poses.at(1).isApprox(moved));
  EXPECT_EQ(log.resets, 0);
}

// The run's first startup_s of keyframes are judged in their window as the others, then once
// more when the keyframes startup_window_after_s later are there (a mover in view from the first
// frame is seen through only once it has left), and mapped then; the others are mapped on time.
TEST(MappingWorker, TheRunsFirstKeyframesAreJudgedAgainBeforeTheyAreMapped) {
  FakeLog log;
  log.released = true;
  StaticPointsOptions options = onlineWindowOptions();
  options.startup_s = 1.0;  // keyframes 0-3 (0.25 s apart)
  options.startup_window_after_s = 3.0;
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), options, 4, nullptr);
  std::uint64_t next = 0;
  const auto pushUpTo = [&](std::uint64_t last) {
    for (; next <= last; ++next) {
      auto kf = std::make_shared<KeyframePacket>(*packet(next));
      kf->timestamp_s = 0.25 * static_cast<double>(next);
      worker.push(kf);
    }
    worker.waitIdle();
    std::lock_guard<std::mutex> lock(log.mutex);
    return log.integrated;
  };
  EXPECT_EQ(pushUpTo(8), (std::vector<std::uint64_t>{4, 5, 6, 7}));  // 2.0 s
  std::vector<std::uint64_t> at_3_5 = pushUpTo(14);                  // 3.5 s: 0.0 to 0.5 s
  std::sort(at_3_5.begin(), at_3_5.end());
  EXPECT_EQ(std::vector<std::uint64_t>(at_3_5.begin(), at_3_5.begin() + 3),
            (std::vector<std::uint64_t>{0, 1, 2}));
  EXPECT_EQ(std::count(at_3_5.begin(), at_3_5.end(), 3u), 0);
  worker.finish();
  std::vector<std::uint64_t> all = log.integrated;
  std::sort(all.begin(), all.end());
  std::vector<std::uint64_t> expected(15);
  for (std::uint64_t i = 0; i < 15; ++i) expected[i] = i;
  EXPECT_EQ(all, expected);
}

// A backend whose cells are votes over views gets the mask grown by fused_mask_dilation_px (3),
// a point backend by mask_dilation_px (5): the fusing one receives the ring between them.
TEST(MappingWorker, FusingBackendsGetTheNarrowerMaskMargin) {
  const auto pointsFor = [](bool fuses, int fused_px) {
    FakeLog log;
    log.released = true;
    StaticPointsOptions options = countingOptions();
    options.fused_mask_dilation_px = fused_px;
    MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace, fuses),
                         SyntheticScene::camera(), options, 4, nullptr);
    worker.push(packet(1));
    worker.finish();
    EXPECT_FALSE(log.points.empty());
    return log.points.empty() ? std::size_t{0} : log.points.front();
  };
  ASSERT_GT(cv::countNonZero(packet(1)->dynamic_mask), 100) << "the scene lost its mover";
  const std::size_t kept_points = pointsFor(false, 3), kept_fused = pointsFor(true, 3);
  EXPECT_GT(kept_fused, kept_points + 50) << "the ring between 3 and 5 px reached neither";
  EXPECT_EQ(pointsFor(true, 5), kept_points);
}

// A box held back in keyframe 0 (masked only for lack of proof that it stands still) that
// keyframes 1 and 2 confirmed static at the same place reaches the map after all; its revised
// mask is reported. With the revision off (voxel 0) keyframe 0 keeps its mask.
TEST(MappingWorker, HeldPixelsConfirmedByOtherKeyframesAreMappedAndTheirMaskRevised) {
  const auto run = [](double voxel_m, std::unordered_map<std::uint64_t, cv::Mat>* revised) {
    FakeLog log;
    log.released = true;
    StaticPointsOptions options = countingOptions();
    options.held_revision_voxel_m = voxel_m;
    MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kReintegrate),
                         SyntheticScene::camera(), options, 4, nullptr);
    for (std::uint64_t id = 0; id < 3; ++id) {
      auto kf = std::make_shared<KeyframePacket>(*packet(0));  // one view, three times
      kf->id = id;
      if (id == 0) {
        kf->held_mask = kf->dynamic_mask.clone();
      } else {
        kf->confirmed_mask = kf->dynamic_mask.clone();
        kf->dynamic_mask = cv::Mat();
      }
      worker.push(kf);
    }
    worker.finish();
    *revised = worker.revisedMasks();
    EXPECT_EQ(log.integrated.size(), 3u);
    return log.points.empty() ? std::size_t{0} : log.points.front();
  };
  const int masked = cv::countNonZero(packet(0)->dynamic_mask);
  ASSERT_GT(masked, 100) << "the scene lost its mover";
  std::unordered_map<std::uint64_t, cv::Mat> revised_on, revised_off;
  const std::size_t on = run(0.03, &revised_on), off = run(0.0, &revised_off);
  EXPECT_TRUE(revised_off.empty());
  ASSERT_EQ(revised_on.count(0), 1u);
  EXPECT_EQ(revised_on.size(), 1u);
  EXPECT_LT(cv::countNonZero(revised_on.at(0)), masked / 10);
  EXPECT_GT(on, off + static_cast<std::size_t>(masked) / 2);
}

// Online, a held-back box that only keyframes more than window_after_s later confirm static gets
// its second look once keyframes held_window_after_s later are there: keyframe 0 goes to the
// backend with the box masked, then the box's pixels follow as its supplement (its id with the
// top bit), which pose updates reach too.
TEST(MappingWorker, HeldPixelsConfirmedSecondsLaterFollowAsASupplement) {
  FakeLog log;
  log.released = true;
  StaticPointsOptions options = countingOptions();
  options.free_space.enabled = false;
  MappingWorker worker(std::make_unique<FakeBackend>(&log, PoseUpdateMode::kInPlace),
                       SyntheticScene::camera(), options, 4, nullptr);
  const double stamps_s[] = {0.0, 1.5, 2.0, 3.5};
  for (std::uint64_t id = 0; id < 4; ++id) {
    auto kf = std::make_shared<KeyframePacket>(*packet(0));  // one view, four times
    kf->id = id;
    kf->timestamp_s = stamps_s[id];
    if (id == 0) {
      kf->held_mask = kf->dynamic_mask.clone();
    } else {
      kf->confirmed_mask = kf->dynamic_mask.clone();
      kf->dynamic_mask = cv::Mat();
    }
    worker.push(kf);
  }
  worker.waitIdle();  // 3.5 s: keyframe 0 judged at 1.5 s (nobody confirmed it yet), looked again
  const std::uint64_t supplement = 0 | MappingWorker::kSupplementBit;
  {
    std::lock_guard<std::mutex> lock(log.mutex);
    ASSERT_GE(log.integrated.size(), 2u);
    EXPECT_EQ(log.integrated[0], 0u);
    EXPECT_NE(std::find(log.integrated.begin(), log.integrated.end(), supplement),
              log.integrated.end());
  }
  const Eigen::Isometry3d moved = Eigen::Translation3d(0.0, 0.02, 0.0) * packet(0)->T_W_C;
  worker.applyPoseUpdates({{0, moved}});
  worker.finish();
  EXPECT_TRUE(log.poses.at(supplement).isApprox(moved));
  const auto revised = worker.revisedMasks();
  ASSERT_EQ(revised.count(0), 1u);
  EXPECT_LT(cv::countNonZero(revised.at(0)), cv::countNonZero(packet(0)->dynamic_mask) / 10);
}

}  // namespace
}  // namespace dynamap::test
