// libFuzzer target: the JSON reader (tools/eval/json_reader.hpp) that reads run.json and
// metrics.json back. Only JsonParseError may come out; a parsed document is walked completely.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_util.hpp"
#include "json_reader.hpp"

namespace {

std::size_t walk(const dynamap::JsonValue& v) {
  std::size_t n = 1;
  for (const auto& item : v.items()) n += walk(item);
  for (const auto& [key, member] : v.members()) {
    n += walk(member);
    if (v.find(key) == nullptr) dynamap::fuzz::fail("member '" + key + "' not found by find()");
    (void)v.number(key);
    (void)v.string(key);
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const dynamap::JsonValue doc = dynamap::parseJson(text, "fuzz");
    (void)walk(doc);
  } catch (const dynamap::JsonParseError&) {
  }
  if (size % 8 == 0) {  // the file path too, now and then
    try {
      (void)dynamap::readJsonFile(dynamap::fuzz::writeScratch("doc.json", text));
    } catch (const dynamap::JsonParseError&) {
    }
  }
  return 0;
}
