#include <gtest/gtest.h>

#include "dynamap/core/dynamic/class_table.hpp"
#include "dynamap/core/dynamic/nms.hpp"

namespace dynamap {
namespace {

int countClass(const std::vector<Detection>& d, int cls) {
  return static_cast<int>(
      std::count_if(d.begin(), d.end(), [&](const Detection& x) { return x.class_id == cls; }));
}

bool hasBoxNear(const std::vector<Detection>& d, const cv::Rect2f& box) {
  return std::any_of(d.begin(), d.end(),
                     [&](const Detection& x) { return iou(x.box, box) > 0.95f; });
}

NmsOptions options(NmsKind kind) {
  NmsOptions o;
  o.kind = kind;
  o.class_score_threshold = ClassTable(DynamicConfig{}).scoreThresholds();
  return o;
}

// Two people side by side, the second partly hidden behind the first (IoU ~0.54), plus a
// duplicate of the first, a faint third person and a dog overlapping the first person.
const std::vector<Detection> kCandidates{
    {cv::Rect2f(100, 50, 100, 200), 0, 0.90f},   // person A
    {cv::Rect2f(103, 52, 100, 200), 0, 0.85f},   // duplicate of A
    {cv::Rect2f(130, 50, 100, 200), 0, 0.60f},   // person B, overlaps A (IoU 0.54)
    {cv::Rect2f(400, 80, 60, 150), 0, 0.18f},    // faint person C
    {cv::Rect2f(120, 150, 90, 90), 16, 0.70f}};  // dog in front of A

TEST(Nms, IouOfKnownBoxes) {
  EXPECT_NEAR(iou(kCandidates[0].box, kCandidates[2].box), 14000.f / 26000.f, 1e-5);
  EXPECT_FLOAT_EQ(iou(cv::Rect2f(0, 0, 10, 10), cv::Rect2f(20, 20, 5, 5)), 0.f);
}

TEST(Nms, PlainDropsTheOverlappingSecondPerson) {
  const auto kept = suppressDuplicates(kCandidates, options(NmsKind::kPlain));
  EXPECT_EQ(countClass(kept, 0), 1);  // A only: B suppressed, C below 0.25
  EXPECT_TRUE(hasBoxNear(kept, kCandidates[0].box));
  EXPECT_FALSE(hasBoxNear(kept, kCandidates[2].box));
  EXPECT_EQ(countClass(kept, 16), 1);  // class-wise: the dog is not suppressed by the person
}

TEST(Nms, RecallOrientedKeepsTheSecondAndTheFaintPerson) {
  const auto kept = suppressDuplicates(kCandidates, options(NmsKind::kRecall));
  EXPECT_TRUE(hasBoxNear(kept, kCandidates[0].box));
  EXPECT_TRUE(hasBoxNear(kept, kCandidates[2].box));  // soft-NMS: score decayed, not dropped
  EXPECT_TRUE(hasBoxNear(kept, kCandidates[3].box));  // person threshold 0.15 < 0.18
  EXPECT_EQ(countClass(kept, 16), 1);
  // Scores are decayed by overlap: B keeps less than its raw 0.60 but stays above threshold.
  for (const auto& d : kept) {
    if (iou(d.box, kCandidates[2].box) > 0.95f) {
      EXPECT_LT(d.score, 0.60f);
      EXPECT_GT(d.score, 0.15f);
    }
  }
  // Sorted by decreasing score.
  for (std::size_t i = 1; i < kept.size(); ++i) EXPECT_GE(kept[i - 1].score, kept[i].score);
}

TEST(Nms, LowDynamicClassesKeepTheHigherThreshold) {
  const std::vector<Detection> cups{{cv::Rect2f(0, 0, 20, 20), 41, 0.2f}};  // cup at 0.2 < 0.25
  EXPECT_TRUE(suppressDuplicates(cups, options(NmsKind::kRecall)).empty());
  EXPECT_FLOAT_EQ(minCandidateScore(options(NmsKind::kRecall)), 0.15f);
  EXPECT_FLOAT_EQ(minCandidateScore(options(NmsKind::kPlain)), 0.25f);
}

TEST(ClassTable, DefaultsAndOverrides) {
  DynamicConfig c;
  const ClassTable t(c);
  EXPECT_EQ(t.size(), 81u);  // COCO's 80 and the class-less mover
  EXPECT_EQ(t.name(0), "person");
  EXPECT_EQ(t.name(ClassTable::kMover), "mover");
  EXPECT_TRUE(t.isHighDynamic(ClassTable::kMover));
  EXPECT_EQ(t.scoreThresholds().size(), 80u);  // the detector's classes only
  EXPECT_TRUE(t.isHighDynamic(ClassTable::classIndex("dog")));
  EXPECT_FALSE(t.isHighDynamic(ClassTable::classIndex("teddy bear")));
  EXPECT_DOUBLE_EQ(t.weight(0), 1.0);
  EXPECT_DOUBLE_EQ(t.weight(ClassTable::classIndex("chair")), 0.5);
  EXPECT_DOUBLE_EQ(t.weight(ClassTable::classIndex("cup")), c.low_dynamic_weight);
  c.class_weights["cup"] = "0.05";
  EXPECT_DOUBLE_EQ(ClassTable(c).weight(ClassTable::classIndex("cup")), 0.05);
  c.class_weights["cup"] = "lots";
  EXPECT_THROW(ClassTable{c}, std::invalid_argument);
  c.class_weights.erase("cup");
  c.high_dynamic_classes.push_back("unicorn");
  try {
    ClassTable bad(c);
    FAIL() << "unknown class accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unicorn"), std::string::npos);
  }
}

}  // namespace
}  // namespace dynamap
