// A third-party backend built outside the dynamap tree: it needs only the public headers
// (dynamap/mapping/plugin_api.hpp) and is compiled by the test build with the compiler directly
// (tests/mapping/mapping_tests.cmake) into its own folder, then found via the registry.
// It counts keyframes and points; parameter "scale" must be a positive number.
#include <cstdlib>
#include <string>

#include "dynamap/mapping/plugin_api.hpp"

namespace {

class ExampleBackend final : public dynamap::MapBackend {
 public:
  explicit ExampleBackend(const dynamap::BackendParams& params) {
    for (const auto& kv : params) {
      if (kv.first != "scale") {
        throw dynamap::MappingError("mapping.params.example." + kv.first + ": unknown parameter");
      }
    }
  }
  void integrate(const dynamap::KeyframeView& view) override {
    ++keyframes_;
    points_ += view.points_C->size();
  }
  void updatePose(std::uint64_t, const Eigen::Isometry3d&) override {}
  dynamap::PoseUpdateMode poseUpdateMode() const override {
    return dynamap::PoseUpdateMode::kInPlace;
  }
  void reset() override { keyframes_ = points_ = 0; }
  void exportMap(const std::string&) override {}
  dynamap::MapStats stats() const override {
    dynamap::MapStats s;
    s.keyframes = keyframes_;
    s.elements = points_;
    s.element_kind = "points";
    return s;
  }

 private:
  std::size_t keyframes_ = 0;
  std::size_t points_ = 0;
};

}  // namespace

DYNAMAP_DEFINE_BACKEND(ExampleBackend)
