// Linked into every test program of a ThreadSanitizer build (DYNAMAP_TSAN) only.
// OpenCV 4.6 ignores OPENCV_FOR_THREADS_NUM for its parallel_for_ unless cv::setNumThreads is
// called, so its TBB pool ran every image loop on uninstrumented workers: each access was a
// (suppressed, see scripts/tsan.supp) race report, and matching 114 k reports against the
// suppressions took 92 % of SyntheticTracking's run time under TSan (250 s for one test).
// Running OpenCV's loops on the calling thread leaves TSan only our own threads to check.
#include <opencv2/core/utility.hpp>

namespace {

struct SequentialOpenCv {
  SequentialOpenCv() { cv::setNumThreads(1); }
};

const SequentialOpenCv kSequentialOpenCv;

}  // namespace
