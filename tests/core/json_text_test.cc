// The one JSON reader (issue 44): nesting bounded before parsing, refusals naming file and line.

#include "core/json_text.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "core/input_error.h"

namespace fvm {
namespace {

using ::testing::HasSubstr;

std::string Message(const std::string& text, int max_depth = kMaxJsonDepth) {
  try {
    ParseJsonText(text, "batch.json", "write {\"identify\": [...]}", max_depth);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(JsonText, RefusesNestingBeyondTheBoundWithItsLineBeforeParsing) {
  // A million levels overflowed the stack of nlohmann-json's recursive destruction (fvm calibrate, SIGSEGV).
  const int n = 1000000;
  const std::string deep = "{\"identify\": [\"a\"],\n\"lens\":\n" + std::string(n, '[') + std::string(n, ']') + "}\n";
  EXPECT_THAT(Message(deep), HasSubstr("batch.json:3: arrays and objects nested deeper than 64 levels"));
  EXPECT_THAT(Message(deep), HasSubstr("write {\"identify\": [...]}"));
}

TEST(JsonText, CountsOnlyBracketsOutsideStrings) {
  const std::string levels = std::string(3, '[') + std::string(3, ']');
  EXPECT_EQ(Message(levels, 3), "");
  EXPECT_THAT(Message("[" + levels + "]", 3), HasSubstr("batch.json:1: arrays and objects nested deeper than 3"));
  // Brackets and escaped quotes inside a string are text.
  const nlohmann::json j = ParseJsonText(R"({"lens": "[[[[\"{{{{"})", "batch.json", "", 1);
  EXPECT_EQ(j["lens"], "[[[[\"{{{{");
}

TEST(JsonText, SyntaxErrorsAndHugeNumbersNameFileAndLine) {
  EXPECT_THAT(Message("{\n  \"identify\": [\"x\",]\n}\n"), HasSubstr("batch.json:2: not valid JSON"));
  EXPECT_THAT(Message("{\"lens\": 1e999}"), HasSubstr("batch.json: not valid JSON"));
  EXPECT_EQ(ParseJsonText("{\"a\": [1, {\"b\": 2}]}", "x.json")["a"][1]["b"], 2);
}

}  // namespace
}  // namespace fvm
