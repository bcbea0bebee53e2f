#include "fvm/option_ranges.h"

#include <fmt/core.h>

#include <cmath>
#include <optional>
#include <string_view>
#include <vector>

#include "core/number_text.h"
#include "imaging/tile_plan.h"

namespace fvm::cli {
namespace {

// The name every range check carries: how --list-numeric-options finds it among an option's checks, followed by
// the fields it prints (FORM, MIN, MAX, whole|real).
constexpr std::string_view kRangeTag = "numbers\t";

std::string ListedFields(const std::string& form, const NumberRange& range) {
  return fmt::format("{}{}\t{}\t{}\t{}", kRangeTag, form, FormatShortest(range.min), FormatShortest(range.max),
                     range.whole ? "whole" : "real");
}

// Digits with an optional sign: how a count is written (CLI11 reads "1e3" as no integer at all).
bool IsWrittenWhole(std::string_view text) {
  text = TrimBlanks(text);
  if (!text.empty() && (text.front() == '+' || text.front() == '-')) text.remove_prefix(1);
  if (text.empty()) return false;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

std::string SingleNumberRefusal(const std::string& text, const NumberRange& range) {
  const std::optional<double> value = ParseDouble(text);
  if (!value) return fmt::format("{} is not a number; give one from {}", QuotedForMessage(text), range.Text());
  std::string refusal = range.Refusal(*value, text);
  if (refusal.empty() && range.whole && !IsWrittenWhole(text)) {
    refusal = fmt::format("{} is not a whole number: write it in digits, e.g. {}", TrimBlanks(text),
                          FormatFixed(*value, 0));
  }
  return refusal;
}

bool IsNumericType(const CLI::Option& option) {
  if (option.get_type_size() == 0) return false;  // a flag
  const std::string type = option.get_type_name();
  const std::string base = type.substr(0, type.find(':'));
  return base == "FLOAT" || base == "INT" || base == "UINT" || base == "NUMBER";
}

// The range check of `option` (its listed fields), or nothing.
std::optional<std::string> RangeFields(CLI::Option& option) {
  for (int k = 0;; ++k) {
    const CLI::Validator* check = nullptr;
    try {
      check = option.get_validator(k);
    } catch (const CLI::OptionNotFound&) {
      return std::nullopt;
    }
    const std::string& name = check->get_name();
    if (name.starts_with(kRangeTag)) return name.substr(kRangeTag.size());
  }
}

std::vector<CLI::App*> CommandsOf(CLI::App& app) {
  std::vector<CLI::App*> all{&app};
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) {
    const std::vector<CLI::App*> below = CommandsOf(*sub);
    all.insert(all.end(), below.begin(), below.end());
  }
  return all;
}

std::string CommandPath(const CLI::App& app) {
  std::string path;
  for (const CLI::App* at = &app; at->get_parent() != nullptr; at = at->get_parent()) {
    path = path.empty() ? at->get_name() : at->get_name() + " " + path;
  }
  return path;
}

}  // namespace

std::string ReadableNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  return fmt::format("{:.6g}", value);
}

std::string NumberRange::Text() const {
  return fmt::format("{} to {}{}", ReadableNumber(min), ReadableNumber(max), unit.empty() ? "" : " " + unit);
}

std::string NumberRange::Refusal(double value, std::string_view written) const {
  const std::string shown = written.empty() ? ReadableNumber(value) : std::string(TrimBlanks(written));
  if (!std::isfinite(value)) return fmt::format("{} is not a finite number; give one from {}", shown, Text());
  if (value < min || value > max) return fmt::format("{}{} is outside {}", shown, unit.empty() ? "" : " " + unit, Text());
  if (std::fpclassify(value) == FP_SUBNORMAL) {
    return fmt::format("{} is a subnormal number (nonzero, yet below 2.2e-308 in size); give 0 or a number from {}", shown,
                       Text());
  }
  if (whole && value != std::floor(value)) return fmt::format("{} is not a whole number (from {})", shown, Text());
  return {};
}

CLI::Validator Within(const NumberRange& range) {
  return CLI::Validator([range](std::string& text) { return SingleNumberRefusal(text, range); }, range.Text(),
                        ListedFields("V", range));
}

CLI::Validator Within(double min, double max, const std::string& unit) { return Within(NumberRange{min, max, unit}); }

CLI::Validator Count(double min, double max) { return Within(NumberRange{min, max, "", true}); }

CLI::Validator NumbersWithin(std::function<std::string(const std::string&)> refusal, const std::string& form,
                             const NumberRange& range, const std::string& description) {
  return CLI::Validator([refusal](std::string& text) { return refusal(text); }, description, ListedFields(form, range));
}

CLI::Validator OverlapCheck(const std::string& what) {
  const NumberRange range{0.01, 99.0, ""};
  const auto refusal = [what](const std::string& text) {
    try {
      const double fraction = imaging::ParseOverlap(text, what);
      if (fraction < 0.01 || fraction > 0.99) {
        return fmt::format("{} '{}': an overlap of {} % leaves nothing to register; give 1 to 99 (%) or 0.01 to 0.99",
                           what, text, ReadableNumber(fraction * 100.0));
      }
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  return NumbersWithin(refusal, "V", range, "PERCENT");
}

std::string NumericOptionList(CLI::App& app) {
  std::string list;
  for (CLI::App* command : CommandsOf(app)) {
    for (CLI::Option* option : command->get_options()) {
      std::optional<std::string> fields = RangeFields(*option);
      if (!fields && !IsNumericType(*option)) continue;
      // An option of several numbers at once (--from X,Y,Z, split by CLI11): one V per number.
      if (fields && fields->starts_with("V\t") && option->get_items_expected_min() > 1) {
        std::string form = "V";
        for (int k = 1; k < option->get_items_expected_min(); ++k) form += ",V";
        fields = form + fields->substr(1);
      }
      // The longest name: what a user types (and what the test passes).
      std::string name = option->get_lnames().empty() ? "-" + option->get_snames().front() : "--" + option->get_lnames().front();
      list += fmt::format("{}\t{}\t{}\n", CommandPath(*command), name, fields ? *fields : "V\tunbounded");
    }
  }
  return list;
}

void RefuseNonFinite(CLI::App& app) {
  const NumberRange finite{-HUGE_VAL, HUGE_VAL, ""};
  for (CLI::App* command : CommandsOf(app)) {
    for (CLI::Option* option : command->get_options()) {
      if (IsNumericType(*option) && !RangeFields(*option)) {
        option->check(CLI::Validator([finite](std::string& text) { return SingleNumberRefusal(text, finite); }, ""));
      }
    }
  }
}

}  // namespace fvm::cli
