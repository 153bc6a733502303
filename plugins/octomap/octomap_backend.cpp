// `octomap`: occupancy octree with ray casting from the camera centre (free space clears
// ghosts). Fast path: each keyframe's points are reduced to the centres of the distinct voxels
// they hit before ray casting (lazy evaluation; inner nodes are updated at export). The rays of
// the newest two keyframes are cast on threads of their own while an older keyframe's cells are
// updated in the tree, in keyframe order (the same updates as insertPointCloud, the same map).
// Exports map.bt, map.ot, grid.pgm + grid.yaml and cloud.ply (occupied voxel centres). A saved
// map's map.ot (importMap()) is the tree's start, to which each rebuild's reset() returns.
#include <cmath>
#include <deque>
#include <filesystem>
#include <future>
#include <memory>

#include <octomap/OcTree.h>

#include "dynamap/mapping/backend_params.hpp"
#include "dynamap/mapping/plugin_api.hpp"
#include "dynamap/mapping/ply_io.hpp"
#include "occupancy_grid.hpp"
#include "octree_file.hpp"
#include "ray_cells.hpp"

namespace dynamap {
namespace {

constexpr double kDefaultResolutionM = 0.03;

class OctomapBackend final : public MapBackend {
 public:
  explicit OctomapBackend(const BackendParams& params) : caster_(kDefaultResolutionM) {
    ParamReader reader("octomap", params);
    resolution_m_ = reader.getDouble("resolution_m", kDefaultResolutionM, 0.005, 10.0);
    max_range_m_ = reader.getDouble("max_range_m", -1.0, -1.0, 1000.0);
    discretize_ = reader.getBool("discretize", true);
    prob_hit_ = reader.getDouble("prob_hit", 0.7, 0.5, 1.0);
    prob_miss_ = reader.getDouble("prob_miss", 0.4, 0.0, 0.5);
    clamp_min_ = reader.getDouble("clamp_min", 0.12, 0.0, 0.5);
    clamp_max_ = reader.getDouble("clamp_max", 0.97, 0.5, 1.0);
    const std::string up = reader.getString("up_axis", "z", {"x", "y", "z", "-x", "-y", "-z"});
    grid_.up_sign = up[0] == '-' ? -1 : 1;
    grid_.up_axis = up.back() - 'x';
    grid_.min_height_m = reader.getDouble("grid_min_height_m", 0.1, -1e4, 1e4);
    grid_.max_height_m = reader.getDouble("grid_max_height_m", 2.0, -1e4, 1e4);
    reader.finish();
    caster_.setResolution(resolution_m_);
    reset();
  }

  void integrate(const KeyframeView& view) override {
    castAndApply(view, +1);
    ++keyframes_;
  }
  bool canDeintegrate() const override { return true; }
  double cellSizeM() const override { return resolution_m_; }
  // The same rays again, their log-odds subtracted: exact but where a cell's clamping cut an
  // update off (a cell at the clamp takes back more than the keyframe had added).
  void deintegrate(const KeyframeView& view) override {
    castAndApply(view, -1);
    if (keyframes_ > 0) --keyframes_;
  }

  // Both poses' rays cast at once (one on another thread) and netted: a cell both poses update
  // alike (most free cells of a move by a few cm) is left alone. The same map as deintegrate()
  // then integrate() but where a cell's clamping cut an update off.
  void moveKeyframe(const KeyframeView& from, const KeyframeView& to) override {
    drain();
    auto to_cells = std::async(std::launch::async, [this, &to] { return castView(to); });
    const plugin::RayCells from_cells = castView(from);
    const plugin::RayCells new_cells = to_cells.get();
    const float hit = tree_->getProbHitLog(), miss = tree_->getProbMissLog();
    // Netted in two halves at once (hundreds of thousands of cells, each a hash look-up), written
    // into the tree one half after the other.
    auto second = std::async(std::launch::async, [&] {
      return plugin::netChange(from_cells, new_cells, hit, miss, 1, 2);
    });
    const auto first = plugin::netChange(from_cells, new_cells, hit, miss, 0, 2);
    applyChange(first);
    applyChange(second.get());
    dirty_inner_ = true;
  }

  void updatePose(std::uint64_t, const Eigen::Isometry3d&) override {}
  PoseUpdateMode poseUpdateMode() const override { return PoseUpdateMode::kReintegrate; }
  bool fusesViews() const override { return true; }
  void reset() override {
    for (auto& cast : pending_) cast.get();
    pending_.clear();
    tree_ = loaded_ ? std::make_unique<octomap::OcTree>(*loaded_)
                    : std::make_unique<octomap::OcTree>(resolution_m_);
    configure(*tree_);
    dirty_inner_ = false;
    keyframes_ = 0;
  }
  bool importMap(const std::string& dir) override {
    loaded_ =
        plugin::readOcTreeFile((std::filesystem::path(dir) / "map.ot").string(), resolution_m_);
    reset();
    return true;
  }

  void exportMap(const std::string& dir) override {
    namespace fs = std::filesystem;
    fs::create_directories(dir);
    finalizeTree();
    const fs::path d(dir);
    writeAtomically((d / "map.bt").string(), [&](const std::string& tmp) {
      if (!tree_->writeBinaryConst(tmp)) throw MappingError(tmp + ": OctoMap write failed");
    });
    writeAtomically((d / "map.ot").string(), [&](const std::string& tmp) {
      if (!tree_->write(tmp)) throw MappingError(tmp + ": OctoMap write failed");
    });
    plugin::writeOccupancyGrid(*tree_, grid_, dir);
    PlyData cloud;
    cloud.vertices = occupiedCentres();
    writeAtomically((d / "cloud.ply").string(),
                    [&](const std::string& tmp) { writePly(tmp, cloud); });
  }

  MapStats stats() const override {
    drain();
    MapStats s;
    s.keyframes = keyframes_;
    for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
      if (tree_->isNodeOccupied(*it)) ++s.elements;
    }
    s.memory_bytes = tree_->memoryUsage();
    s.element_kind = "occupied_cells";
    return s;
  }

 private:
  struct Cells : plugin::RayCells {
    int sign = +1;  ///< -1: a keyframe taken out
  };
  /// The view's points reduced to distinct voxel centres (discretize_), its rays cast on a thread
  /// of its own (each with `sign`); with more than kCastsInFlight casts under way, the oldest's
  /// cells are written into the tree meanwhile (a rebuild keeps both cores casting).
  void castAndApply(const KeyframeView& view, int sign) {
    octomap::Pointcloud cloud = worldCloud(view);
    pending_.push_back(std::async(std::launch::async, &OctomapBackend::castCells, this,
                                  std::move(cloud), originOf(view), sign));
    while (pending_.size() > kCastsInFlight) applyOldestCast();
    dirty_inner_ = true;
  }
  std::unique_ptr<Cells> castCells(const octomap::Pointcloud& cloud, octomap::point3d origin,
                                   int sign) const {
    auto cells = std::make_unique<Cells>();
    static_cast<plugin::RayCells&>(*cells) = plugin::castRays(caster_, cloud, origin, max_range_m_);
    cells->sign = sign;
    return cells;
  }
  void applyOldestCast() const {
    const std::unique_ptr<Cells> cells = pending_.front().get();
    pending_.pop_front();
    apply(*cells);
  }
  /// The view's points in the world frame (reduced to distinct voxel centres: discretize_).
  octomap::Pointcloud worldCloud(const KeyframeView& view) const {
    const Eigen::Isometry3f T = view.T_W_C.cast<float>();
    if (discretize_) return plugin::distinctCellCentres(*tree_, *view.points_C, T);
    octomap::Pointcloud cloud;
    cloud.reserve(view.points_C->size());
    for (const auto& p_C : *view.points_C) {
      const Eigen::Vector3f p = T * p_C;
      cloud.push_back(p.x(), p.y(), p.z());
    }
    return cloud;
  }
  static octomap::point3d originOf(const KeyframeView& view) {
    const Eigen::Vector3d o = view.T_W_C.translation();
    return {static_cast<float>(o.x()), static_cast<float>(o.y()), static_cast<float>(o.z())};
  }
  plugin::RayCells castView(const KeyframeView& view) const {
    return plugin::castRays(caster_, worldCloud(view), originOf(view), max_range_m_);
  }
  /// This run's sensor model and clamping (a loaded tree keeps its log-odds, not its model).
  void configure(octomap::OcTree& tree) const {
    tree.setProbHit(prob_hit_);
    tree.setProbMiss(prob_miss_);
    tree.setClampingThresMin(clamp_min_);
    tree.setClampingThresMax(clamp_max_);
  }
  /// insertPointCloud's updates: the free cells, then the occupied ones (taken back in the
  /// opposite order).
  void apply(const Cells& cells) const {
    if (cells.sign > 0) {
      for (const auto& key : cells.free) tree_->updateNode(key, false, /*lazy_eval=*/true);
      for (const auto& key : cells.occupied) tree_->updateNode(key, true, /*lazy_eval=*/true);
      return;
    }
    for (const auto& key : cells.occupied) takeBack(key, -tree_->getProbHitLog());
    for (const auto& key : cells.free) takeBack(key, -tree_->getProbMissLog());
  }
  void applyChange(const std::vector<plugin::CellChange>& change) const {
    for (const plugin::CellChange& c : change) {
      if (c.taken_back) {
        takeBack(c.key, c.log_odds);
      } else {
        tree_->updateNode(c.key, c.log_odds, /*lazy_eval=*/true);
      }
    }
  }
  /// A cell back at log-odds 0 is no longer known (OctoMap takes 0 as occupied): it is deleted,
  /// or, where it is its parent's only child, left free by a hair, which the grid takes as
  /// unknown (Debian's OctoMap 1.9.7 asserts when deleteNode() empties a parent: the emptied
  /// child array is never freed).
  void takeBack(const octomap::OcTreeKey& key, float delta) const {
    octomap::OcTreeNode* node = tree_->search(key);
    if (node == nullptr) return;
    if (std::fabs(node->getLogOdds() + delta) >= plugin::kUnknownLogOdds) {
      tree_->updateNode(key, delta, /*lazy_eval=*/true);
      return;
    }
    if (hasSibling(key)) {
      tree_->deleteNode(key);
    } else {
      node->setLogOdds(-0.5f * plugin::kUnknownLogOdds);
    }
  }
  bool hasSibling(const octomap::OcTreeKey& key) const {
    const unsigned depth = tree_->getTreeDepth();
    const octomap::OcTreeNode* parent = tree_->search(key, depth - 1);
    if (parent == nullptr) return false;
    int children = 0;
    for (unsigned i = 0; i < 8; ++i) children += tree_->nodeChildExists(parent, i) ? 1 : 0;
    return children > 1;
  }
  void drain() const {
    while (!pending_.empty()) applyOldestCast();
  }
  void finalizeTree() {
    drain();
    if (dirty_inner_) tree_->updateInnerOccupancy();
    dirty_inner_ = false;
  }

  // Centres of the occupied finest-level voxels (pruned nodes expanded).
  std::vector<Eigen::Vector3f> occupiedCentres() const {
    std::vector<Eigen::Vector3f> out;
    const double res = tree_->getResolution();
    const unsigned max_depth = tree_->getTreeDepth();
    for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
      if (!tree_->isNodeOccupied(*it)) continue;
      const int n = 1 << (max_depth - it.getDepth());
      const octomap::point3d c = it.getCoordinate();
      const double h = it.getSize() / 2 - res / 2;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
          for (int k = 0; k < n; ++k)
            out.emplace_back(c.x() - h + i * res, c.y() - h + j * res, c.z() - h + k * res);
    }
    return out;
  }

  static constexpr std::size_t kCastsInFlight = 2;
  // The last keyframes' cells are applied when the map is next read, by const readers too.
  std::unique_ptr<octomap::OcTree> tree_;
  std::unique_ptr<const octomap::OcTree> loaded_;  ///< importMap()'s tree, of no keyframe
  octomap::OcTree caster_;  ///< the key grid and ray traversal of the casting thread; no map
  mutable std::deque<std::future<std::unique_ptr<Cells>>> pending_;  ///< oldest first
  double resolution_m_ = kDefaultResolutionM;
  double prob_hit_ = 0.7, prob_miss_ = 0.4, clamp_min_ = 0.12, clamp_max_ = 0.97;
  double max_range_m_ = -1.0;
  bool discretize_ = true;
  plugin::GridOptions grid_;
  std::size_t keyframes_ = 0;
  bool dirty_inner_ = false;
};

}  // namespace
}  // namespace dynamap

DYNAMAP_DEFINE_BACKEND(dynamap::OctomapBackend)
