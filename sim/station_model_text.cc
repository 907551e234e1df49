#include "sim/station_model_text.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

namespace irdist::sim {

bool ParseProtocolInt(const std::string& text, long long* value) {
  if (text.empty()) return false;
  std::size_t i = (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (i == text.size() || text.size() > 12) return false;
  for (std::size_t k = i; k < text.size(); ++k) {
    if (text[k] < '0' || text[k] > '9') return false;
  }
  *value = std::strtoll(text.c_str(), nullptr, 10);
  return true;
}

int StationRequest::Ints(std::size_t n, std::vector<long long>* out) const {
  if (args.size() < n) return -109;
  if (args.size() > n) return -108;
  for (const std::string& a : args) {
    long long v = 0;
    if (!ParseProtocolInt(a, &v)) return -104;
    out->push_back(v);
  }
  return 0;
}

int StationRequest::AxisAndInts(std::size_t n, int* axis, std::vector<long long>* out) const {
  if (args.size() != n + 1) return args.size() < n + 1 ? -109 : -108;
  const std::string name = Upper(args[0]);
  *axis = name == "SLIDE" ? 0 : name == "PAN" ? 1 : name == "TILT" ? 2 : -1;
  if (*axis < 0) return -104;
  StationRequest rest;
  rest.args.assign(args.begin() + 1, args.end());
  return rest.Ints(n, out);
}

CommandError ErrorFor(int code) {
  switch (code) {
    case -102: return {code, "Syntax error"};
    case -104: return {code, "Data type error"};
    case -108: return {code, "Parameter not allowed"};
    case -109: return {code, "Missing parameter"};
    case -113: return {code, "Undefined header"};
    case -221: return {code, "Settings conflict"};
    case -222: return {code, "Data out of range"};
    case -350: return {code, "Queue overflow"};
    case -500: return {code, "Power on"};
    case 201: return {code, "Not homed"};
    case 202: return {code, "Emergency stop active"};
    case 203: return {code, "Checksum mismatch"};
    case 204: return {code, "Homing failed"};
    case 205: return {code, "Line too long"};
    case 206: return {code, "Link lost"};
    default: return {code, "Execution error"};
  }
}

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> out;
  if (text.empty()) return out;
  std::string cur;
  for (char c : text) {
    if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  return out;
}

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

long long Centi(double v) { return std::llround(v * 100.0); }

std::string CentiList(const std::vector<double>& values) {
  std::string text;
  for (double v : values) text += (text.empty() ? "" : ",") + std::to_string(Centi(v));
  return text;
}

}  // namespace irdist::sim
