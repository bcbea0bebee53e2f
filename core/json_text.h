#pragma once
// The one JSON reader of the inputs (batch.json, stations, truth files, test-piece descriptions, calibrations):
// nesting bounded before nlohmann-json sees the text, and every refusal naming the file and the line.
//
// Why a bound: nlohmann-json builds and destroys a value recursively, one stack frame per level, so a file of a
// million nested arrays (2 MB) overflowed the stack (fvm calibrate died with SIGSEGV, issue 44). A pre-scan of the
// brackets outside strings costs one pass over the bytes and stops at the first level too deep, with its line. No
// file fvm reads nests beyond 5 levels; 64 leaves room for hand-written ones.

#include <cstddef>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace fvm {

constexpr int kMaxJsonDepth = 64;

// Parses `text`; `name` stands for the file in messages and `hint` (e.g. "write {\"stations\": [...]}") ends them.
// Throws InputError "NAME:LINE: not valid JSON (why); HINT" on a syntax error or a number beyond double, and
// "NAME:LINE: arrays and objects nested deeper than 64 levels; HINT" before parsing when the text nests too deep.
nlohmann::json ParseJsonText(std::string_view text, const std::string& name, std::string_view hint = {},
                             int max_depth = kMaxJsonDepth);

// The same for a file read whole (ReadFileBytes: missing, unreadable or larger than max_bytes throws).
nlohmann::json ReadJsonFile(const std::filesystem::path& path, std::string_view hint = {},
                            std::size_t max_bytes = std::size_t{1} << 28);

}  // namespace fvm
