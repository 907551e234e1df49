#include "base/yaml_fields.h"

#include "base/regular_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace irdist::yaml_fields {
namespace {

// A scalar as quoted in a message: at most 40 characters, control characters shown as '?'.
std::string Quoted(const std::string& text) {
  constexpr size_t kMaxShown = 40;
  std::string shown = text.substr(0, kMaxShown);
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  return "'" + shown + (text.size() > kMaxShown ? "...'" : "'");
}

std::string TypeName(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing";
    case YAML::NodeType::Scalar:
      return Quoted(node.Scalar());
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Undefined:
      return "nothing";
  }
  return "?";
}

size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      const size_t substitution = diagonal + (a[i - 1] == b[j - 1] ? 0 : 1);
      row[j] = std::min({above + 1, row[j - 1] + 1, substitution});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

void Fail(const std::string& file, const YAML::Mark& mark, const std::string& message) {
  if (mark.is_null()) throw InputError(file, 0, 0, message);
  throw InputError(file, mark.line + 1, mark.column + 1, message);
}

YAML::Node Parse(const std::string& text, const std::string& file) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    Fail(file, e.mark, "YAML syntax error: " + e.msg);
  }
}

std::string ReadFile(const std::string& path) {
  std::string text, why;
  if (!ReadRegularFile(path, kMaxInputTextBytes, &text, &why)) {
    throw InputError(path, 0, 0,
                     "cannot open the file (it " + why + "); check the path (relative paths are "
                     "taken from the current directory) and give a regular file");
  }
  return text;
}

std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_distance = 0;
  for (const std::string& candidate : candidates) {
    // The distance is at least the lengths' difference: a candidate that cannot come closer is
    // skipped (a fuzzed key of kilobytes against each allowed name took 5-10% of a loader's time).
    const size_t length_gap = word.size() > candidate.size() ? word.size() - candidate.size()
                                                            : candidate.size() - word.size();
    if (!best.empty() && length_gap >= best_distance) continue;
    const size_t distance = EditDistance(word, candidate);
    if (best.empty() || distance < best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  const bool prefix = !best.empty() && !word.empty() && best.rfind(word, 0) == 0;
  if (best_distance <= std::max<size_t>(2, word.size() / 3) || prefix) return best;
  return "";
}

std::string JoinNames(const std::vector<std::string>& names) {
  std::string joined;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) joined += ", ";
    joined += names[i];
  }
  return joined;
}

MapReader::MapReader(const YAML::Node& node, std::string file, std::string context,
                     std::vector<std::string> allowed)
    : node_(node),
      file_(std::move(file)),
      context_(std::move(context)),
      allowed_(std::move(allowed)),
      mark_(node.Mark()) {
  if (!node_.IsMap()) {
    // The kind only, never the text: a file that is not YAML at all (`rig: ../../etc/passwd`)
    // reads as one long scalar, and its content has no place in an error message.
    const std::string kind = node_.IsScalar() ? "a single text value" : TypeName(node_);
    Fail(file_, mark_,
         context_ + " must be a map with keys " + JoinNames(allowed_) + ", not " + kind +
             "; check that this is the right file and its indentation");
  }
  std::vector<std::string> seen;
  for (const auto& entry : node_) {
    const YAML::Node& key = entry.first;
    if (!key.IsScalar()) Fail(file_, key.Mark(), "keys of " + context_ + " must be names");
    const std::string name = key.Scalar();
    if (std::find(allowed_.begin(), allowed_.end(), name) == allowed_.end()) {
      std::string message = "unknown key " + Quoted(name) + " in " + context_ +
                            "; valid keys: " + JoinNames(allowed_);
      const std::string closest = ClosestMatch(name, allowed_);
      if (!closest.empty()) message += " (did you mean '" + closest + "'?)";
      Fail(file_, key.Mark(), message);
    }
    if (std::find(seen.begin(), seen.end(), name) != seen.end()) {
      Fail(file_, key.Mark(), "key '" + name + "' appears twice in " + context_);
    }
    seen.push_back(name);
  }
}

bool MapReader::Has(const std::string& key) const { return static_cast<bool>(node_[key]); }

YAML::Node MapReader::Get(const std::string& key) const { return node_[key]; }

YAML::Node MapReader::Require(const std::string& key) const {
  YAML::Node value = node_[key];
  if (!value) Fail(file_, mark_, context_ + " is missing the key '" + key + "'");
  return value;
}

double MapReader::Number(const std::string& key, double fallback) const {
  return Has(key) ? AsNumber(Get(key), file_, key) : fallback;
}

double MapReader::Bounded(const std::string& key, double fallback, const Bound& bound,
                          const std::string& fix) const {
  if (!Has(key)) return fallback;
  return AsBounded(Get(key), file_, context_ + "." + key, bound, fix);
}

int MapReader::Integer(const std::string& key, int fallback) const {
  return Has(key) ? AsInteger(Get(key), file_, key) : fallback;
}

bool MapReader::Boolean(const std::string& key, bool fallback) const {
  return Has(key) ? AsBoolean(Get(key), file_, key) : fallback;
}

std::string MapReader::String(const std::string& key, const std::string& fallback) const {
  return Has(key) ? AsString(Get(key), file_, key) : fallback;
}

double AsNumber(const YAML::Node& node, const std::string& file, const std::string& what) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
    Fail(file, node.Mark(), what + " must be a number, not " + TypeName(node));
  }
  return value;
}

double AsBounded(const YAML::Node& node, const std::string& file, const std::string& what,
                 const Bound& bound, const std::string& fix) {
  const double value = AsNumber(node, file, what);
  const std::string refusal = bound.Refusal(what, value, fix);
  if (!refusal.empty()) Fail(file, node.Mark(), refusal);
  return value;
}

int AsInteger(const YAML::Node& node, const std::string& file, const std::string& what) {
  double value = 0.0;
  if (!node.IsScalar() || !YAML::convert<double>::decode(node, value) || !std::isfinite(value) ||
      value != std::floor(value)) {
    Fail(file, node.Mark(), what + " must be a whole number, not " + TypeName(node));
  }
  if (std::abs(value) > kMaxInteger) {
    Fail(file, node.Mark(),
         what + " " + Quoted(node.Scalar()) + " is out of range; whole numbers here lie in [-" +
             std::to_string(kMaxInteger) + ", " + std::to_string(kMaxInteger) + "]");
  }
  return static_cast<int>(value);
}

bool AsBoolean(const YAML::Node& node, const std::string& file, const std::string& what) {
  bool value = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
    Fail(file, node.Mark(), what + " must be true or false, not " + TypeName(node));
  }
  return value;
}

std::string AsString(const YAML::Node& node, const std::string& file, const std::string& what) {
  if (!node.IsScalar())
    Fail(file, node.Mark(), what + " must be a text value, not " + TypeName(node));
  return node.Scalar();
}

}  // namespace irdist::yaml_fields
