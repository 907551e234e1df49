#pragma once
// Strict reading of YAML files for recipes and rig files: every key known, every value of the
// right type, and every error an InputError naming file:line:column and what would be valid.
// Shared by every reader of YAML files (app/ for recipes and rig files, sim/ for the rig file's
// virtual: section, station/ drivers for their own rig-file sections): one strictness everywhere.
// This header exposes yaml-cpp types: include it from .cc files only, never from a public header.

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "base/bounds.h"
#include "base/input_error.h"

namespace irdist::yaml_fields {

// Throws InputError at `mark` (yaml-cpp marks are 0-based; the error is 1-based).
[[noreturn]] void Fail(const std::string& file, const YAML::Mark& mark, const std::string& message);

// Parses YAML text; a syntax error becomes an InputError with its position. An empty document
// yields a Null node.
YAML::Node Parse(const std::string& text, const std::string& file);

// Reads the whole file; throws InputError (line 0) when it cannot be read.
std::string ReadFile(const std::string& path);

// The closest candidate to `word` by edit distance, or "" when none is close.
std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates);

// "a, b, c"
std::string JoinNames(const std::vector<std::string>& names);

// A YAML map whose keys must all be in `allowed`; duplicate keys are errors too.
class MapReader {
 public:
  // `context` names the section in messages ("bracket", "the recipe", "station.limits").
  MapReader(const YAML::Node& node, std::string file, std::string context,
            std::vector<std::string> allowed);

  bool Has(const std::string& key) const;
  // The value node; throws "missing key" at the map's position when absent.
  YAML::Node Require(const std::string& key) const;
  // The value node, or an undefined node when absent.
  YAML::Node Get(const std::string& key) const;
  const YAML::Mark& Mark() const { return mark_; }
  const std::string& File() const { return file_; }

  double Number(const std::string& key, double fallback) const;
  // A number inside `bound` (base/bounds.h), refused at its file:line:column with the range,
  // the physics and `fix`; `fallback` when absent.
  double Bounded(const std::string& key, double fallback, const Bound& bound,
                 const std::string& fix = "") const;
  int Integer(const std::string& key, int fallback) const;
  bool Boolean(const std::string& key, bool fallback) const;
  std::string String(const std::string& key, const std::string& fallback) const;

 private:
  YAML::Node node_;
  std::string file_;
  std::string context_;
  std::vector<std::string> allowed_;
  YAML::Mark mark_;
};

// The largest magnitude AsInteger accepts: far from int overflow in any sum of a few of them.
constexpr int kMaxInteger = 2000000000;

// Scalar conversions; `what` names the value in messages ("bracket.t_ref_ms"). Messages quote at
// most 40 characters of a value.
double AsNumber(const YAML::Node& node, const std::string& file, const std::string& what);
int AsInteger(const YAML::Node& node, const std::string& file, const std::string& what);
// A number inside `bound`, refused at the node's position with the range, the physics and `fix`.
double AsBounded(const YAML::Node& node, const std::string& file, const std::string& what,
                 const Bound& bound, const std::string& fix = "");
bool AsBoolean(const YAML::Node& node, const std::string& file, const std::string& what);
std::string AsString(const YAML::Node& node, const std::string& file, const std::string& what);

}  // namespace irdist::yaml_fields
