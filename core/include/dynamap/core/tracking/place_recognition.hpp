#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

namespace cv::flann {
class Index;
}

namespace dynamap {

struct PlaceRecognitionParams {
  int max_hamming = 50;      ///< a descriptor pair farther apart casts no vote
  int neighbours = 4;        ///< nearest descriptors looked at per query descriptor and chunk
  int chunk_keyframes = 16;  ///< keyframes brute-forced before they go into an LSH chunk
  int lsh_tables = 8;        ///< FLANN LSH: hash tables, ...
  int lsh_key_bits = 16;     ///< ... bits of a hash key ...
  int lsh_multi_probe = 1;   ///< ... and multi-probe level
};

/// An earlier keyframe that looks like the query: `keyframe` as given to add().
struct PlaceCandidate {
  int keyframe = -1;
  int votes = 0;  ///< query descriptors with a descriptor of this keyframe within max_hamming
};

/// Place recognition over keyframes' binary (ORB) descriptors: every query descriptor votes
/// once for each keyframe holding one of its nearest descriptors within `max_hamming`.
/// The newest keyframes are brute-forced; older ones sit in OpenCV FLANN LSH indexes built in
/// chunks that merge as they grow (sizes 16, 32, 64, ... keyframes, like a binary counter), so
/// adding is amortised O(log n) rebuilds per descriptor and a query visits O(log n) indexes.
/// Not thread-safe: one owner (the loop closer's thread).
class PlaceRecognizer {
 public:
  explicit PlaceRecognizer(const PlaceRecognitionParams& params = {});
  ~PlaceRecognizer();
  PlaceRecognizer(const PlaceRecognizer&) = delete;
  PlaceRecognizer& operator=(const PlaceRecognizer&) = delete;

  /// Adds keyframe `keyframe` (any int, e.g. a dense index) with its descriptors (N x 32 CV_8U,
  /// static features only: see LoopCloser).
  void add(int keyframe, const cv::Mat& descriptors);
  /// Keyframes for which `allowed(keyframe)` holds, most votes first, at most `max_results`.
  std::vector<PlaceCandidate> query(const cv::Mat& descriptors,
                                    const std::function<bool(int)>& allowed,
                                    int max_results) const;
  int size() const { return keyframes_; }

 private:
  struct Chunk {
    cv::Mat descriptors;     ///< stacked; kept alive for the index
    std::vector<int> owner;  ///< keyframe of each row
    int keyframes = 0;
    std::unique_ptr<cv::flann::Index> index;  ///< null while brute-forced (the newest chunk)
  };
  void seal();  ///< indexes the brute-forced chunk, then merges equal-sized neighbours
  void buildIndex(Chunk& chunk) const;
  /// For each query row, the keyframes (owner) of its near descriptors in `chunk`.
  void vote(const Chunk& chunk, const cv::Mat& query, std::vector<std::vector<int>>& hits) const;

  PlaceRecognitionParams params_;
  std::vector<Chunk> chunks_;  ///< indexed ones, biggest first
  Chunk recent_;               ///< brute-forced
  int keyframes_ = 0;
};

}  // namespace dynamap
