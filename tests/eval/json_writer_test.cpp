#include "json_writer.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include <gtest/gtest.h>

namespace dynamap {
namespace {

TEST(JsonWriter, EscapesStringsAndWritesNumbersThatReadBack) {
  EXPECT_EQ(jsonString("a\"b\\c\nd\x01"), "\"a\\\"b\\\\c\\nd\\u0001\"");
  for (double v : {0.1, 1.0 / 3.0, 0.008143967169519543, -2.5e-12, 1e300}) {
    EXPECT_EQ(std::strtod(jsonNumber(v).c_str(), nullptr), v) << jsonNumber(v);
  }
  EXPECT_EQ(jsonNumber(0.5), "0.5");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(jsonNumber(std::numeric_limits<double>::infinity()), "null");
}

TEST(JsonWriter, NestedObjectsCompactAndPretty) {
  JsonObject inner;
  inner.add("n", 3).add("ok", true);
  JsonObject root;
  root.add("name", "x").add("inner", inner).add("v", 0.25).addRaw("list", "[1,2]");
  EXPECT_EQ(root.str(),
            "{\"name\":\"x\",\"inner\":{\"n\":3,\"ok\":true},\"v\":0.25,\"list\":[1,2]}");
  EXPECT_EQ(root.str(2),
            "{\n  \"name\": \"x\",\n  \"inner\": {\n    \"n\": 3,\n    \"ok\": true\n  },\n"
            "  \"v\": 0.25,\n  \"list\": [1,2]\n}");
  EXPECT_EQ(JsonObject().str(), "{}");
}

}  // namespace
}  // namespace dynamap
