// libFuzzer target: the run documents as the HTML report reads them back (run.json,
// metrics.json, timings.json: readJsonFile with nlohmann-json, then every member walked by
// writeHtmlReport whatever its type). Input: the same text goes into the file named by the
// first byte. Nothing may throw out of writeHtmlReport except "cannot write report.html", and
// a document that parses must survive dumpJson -> parse unchanged.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "fuzz_util.hpp"
#include "html_report.hpp"
#include "json_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kNames[] = {"run.json", "metrics.json", "timings.json"};
  const std::string name = kNames[data[0] % 3];
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::string dir = dynamap::fuzz::scratchDir() + "/run";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = dynamap::fuzz::writeScratch("run/" + name, text);

  try {
    const dynamap::Json doc = dynamap::readJsonFile(path);
    const std::string dumped = dynamap::dumpJson(doc);
    if (dynamap::Json::parse(dumped) != doc && dumped.find("null") == std::string::npos &&
        dumped.find("\xef\xbf\xbd") == std::string::npos) {
      dynamap::fuzz::fail("dumpJson -> parse changed the document: " + dumped);
    }
  } catch (const std::runtime_error&) {  // invalid JSON, named by file
  }
  (void)dynamap::writeHtmlReport(dir, "fuzz", "");
  return 0;
}
