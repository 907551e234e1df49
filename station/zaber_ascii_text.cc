#include "station/zaber_ascii_text.h"

#include <algorithm>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

namespace irdist::zaber_ascii_text {

bool ParseAddress(const std::string& text, Address* out) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  if (words.empty() || words.size() > 2) return false;
  for (const std::string& w : words) {
    if (w.size() > 2 || w.find_first_not_of("0123456789") != std::string::npos) return false;
  }
  Address a;
  a.device = std::stoi(words[0]);
  a.axis = words.size() == 2 ? std::stoi(words[1]) : 1;
  if (a.device < 1 || a.device > 99 || a.axis < 1 || a.axis > 9) return false;
  *out = a;
  return true;
}

std::string Lrc(const std::string& body) {
  unsigned sum = 0;
  for (unsigned char c : body) sum += c;
  char hex[3];
  std::snprintf(hex, sizeof(hex), "%02X", (256u - (sum & 0xFFu)) & 0xFFu);
  return hex;
}

bool ParseReply(std::string line, bool need_checksum, Reply* out, bool* checked) {
  if (line.size() < 2 || (line[0] != '@' && line[0] != '#' && line[0] != '!')) return false;
  const std::size_t colon = line.rfind(':');
  *checked = colon != std::string::npos && colon + 3 == line.size();
  if (*checked) {
    const std::string body = line.substr(1, colon - 1);
    if (Lrc(body) != line.substr(colon + 1)) return false;
    line.resize(colon);
  } else if (need_checksum) {
    return false;
  }
  std::istringstream in(line.substr(1));
  Reply r;
  r.type = line[0];
  if (!(in >> r.device >> r.axis)) return false;
  std::string token;
  if (!(in >> token)) return r.type == '!' ? (*out = r, true) : false;
  if (token.size() <= 2 &&
      std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    r.id = std::stoi(token);
    if (!(in >> token)) return false;
  }
  if (r.type == '@') {
    r.flag = token;
    if (r.flag != "OK" && r.flag != "RJ") return false;
    if (!(in >> r.status >> r.warning)) return false;
    if (r.status != "IDLE" && r.status != "BUSY") return false;
  }
  std::getline(in >> std::ws, r.data);
  *out = r;
  return true;
}

std::string FlagMeaning(const std::string& flag) {
  static const std::pair<const char*, const char*> kFlags[] = {
      {"FF", "critical system error"},      {"FD", "driver disabled"},
      {"FQ", "encoder error"},              {"FS", "stalled and stopped"},
      {"FT", "excessive twist"},            {"FE", "limit error"},
      {"FB", "stream bounds error"},        {"FP", "interpolated path deviation"},
      {"FM", "motor temperature error"},    {"FO", "driver over temperature/current"},
      {"WR", "no reference position"},      {"WH", "device not homed"},
      {"WL", "unexpected limit trigger"},   {"WV", "voltage out of range"},
      {"WT", "system temperature high"},    {"WM", "displaced when stationary"},
      {"WS", "stalled"},                    {"WP", "invalid calibration"},
      {"NC", "manual control"},             {"NI", "command interrupted"},
      {"ND", "stream discontinuity"},       {"NU", "setting update pending"},
      {"NJ", "joystick calibrating"}};
  for (const auto& [code, text] : kFlags) {
    if (flag == code) return text;
  }
  return "flag not in the manual's table";
}

bool Unreferenced(const std::string& flag) { return flag == "WR" || flag == "WH"; }

bool IsIntegers(const std::string& data) {
  std::istringstream in(data);
  int count = 0;
  for (std::string word; in >> word; ++count) {
    const std::size_t digits = word[0] == '-' ? 1 : 0;
    if (word.size() == digits || word.find_first_not_of("0123456789", digits) != std::string::npos)
      return false;
  }
  return count > 0;
}

bool Fault(const std::string& flag) { return !flag.empty() && flag[0] == 'F'; }

std::string RejectionFix(const std::string& reason) {
  if (reason == "BADDATA") return "the value is out of the axis's range (check limit.min/max)";
  if (reason == "BADCOMMAND") return "the firmware does not know the command; check its version";
  if (reason == "BADAXIS" || reason == "DEVICEONLY")
    return "check the axis numbers in the rig file's `axes:`";
  if (reason == "PARKED") return "unpark the axis (`tools parking unpark`)";
  if (reason == "DRIVERDISABLED") return "enable the driver (`driver enable`) and check power";
  if (reason == "BADMESSAGEID") return "a firmware bug or a garbled id; retry";
  if (reason == "AGAIN" || reason == "STATUSBUSY") return "the device is busy; retry later";
  return "see the manual's list of rejection reasons";
}

}  // namespace irdist::zaber_ascii_text
