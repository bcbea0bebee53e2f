#include "core/json_text.h"

#include <fmt/core.h>

#include <algorithm>

#include "core/file_io.h"
#include "core/input_error.h"

namespace fvm {
namespace {

int LineAt(std::string_view text, std::size_t byte) {
  byte = std::min(byte, text.size());
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(byte), '\n'));
}

std::string Ending(std::string_view hint) { return hint.empty() ? std::string() : "; " + std::string(hint); }

// Throws at the first '[' or '{' outside a string that opens level max_depth + 1.
void CheckDepth(std::string_view text, const std::string& name, std::string_view hint, int max_depth) {
  int depth = 0, line = 1;
  bool in_string = false, escaped = false;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        throw InputError(fmt::format("{}:{}: arrays and objects nested deeper than {} levels, as no file fvm reads "
                                     "is; check that it is the file meant{}",
                                     name, line, max_depth, Ending(hint)));
      }
    } else if (c == ']' || c == '}') {
      --depth;  // unbalanced text is the parser's to report
    }
  }
}

}  // namespace

nlohmann::json ParseJsonText(std::string_view text, const std::string& name, std::string_view hint, int max_depth) {
  CheckDepth(text, name, hint, max_depth);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(fmt::format("{}:{}: not valid JSON ({}){}", name, LineAt(text, e.byte), e.what(), Ending(hint)));
  } catch (const nlohmann::json::exception& e) {  // a number beyond double is out_of_range, not parse_error
    throw InputError(fmt::format("{}: not valid JSON ({}){}", name, e.what(), Ending(hint)));
  }
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path, std::string_view hint, std::size_t max_bytes) {
  return ParseJsonText(ReadFileBytes(path, max_bytes), path.string(), hint);
}

}  // namespace fvm
