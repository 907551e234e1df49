#include "station/flir_ptu_text.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace irdist::ptu_text {
namespace {

std::string Upper(std::string text) {
  for (char& c : text) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return text;
}

// "PP", "TP-40", "1200", "A", "PS2000": the words of a PTU command line.
bool IsCommandWord(const std::string& word) {
  std::size_t i = 0;
  while (i < word.size() && std::isalpha(static_cast<unsigned char>(word[i]))) ++i;
  if (i > 2) return false;
  if (i < word.size() && (word[i] == '-' || word[i] == '+')) ++i;
  const std::size_t digits = i;
  while (i < word.size() && std::isdigit(static_cast<unsigned char>(word[i]))) ++i;
  return i == word.size() && (digits > 0 || i > 0) && i - digits <= 10;
}

}  // namespace

bool IsLimitHit(const std::string& line) {
  const std::size_t mark = line.find('!');
  if (mark == std::string::npos) return false;
  std::string text = line.substr(mark + 1);
  text.erase(0, text.find_first_not_of(' '));
  text.erase(text.find_last_not_of(' ') + 1);
  return text == "P" || text == "T";
}

bool IsRateCommand(const std::string& command) {
  return command.size() >= 2 && (command[0] == 'P' || command[0] == 'T') &&
         std::string("SAULB").find(command[1]) != std::string::npos;
}

bool FirstNumber(const std::string& text, double* value) {
  std::istringstream in(text);
  for (std::string word; in >> word;) {
    while (!word.empty() && (word.back() == ',' || word.back() == '.')) word.pop_back();
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (!word.empty() && end == word.c_str() + word.size() && std::isfinite(v)) {
      *value = v;
      return true;
    }
  }
  return false;
}

bool NamesAPanTiltUnit(const std::string& line) {
  const std::string upper = Upper(line);
  return upper.find("PAN-TILT") != std::string::npos || upper.find("PTU") != std::string::npos;
}

bool IsPowerUpText(const std::string& line) {
  if (line.find_first_of("*!") != std::string::npos) return false;
  return NamesAPanTiltUnit(line) || Upper(line).find("INITIALIZING") != std::string::npos;
}

bool IsResetChatter(const std::string& line) {
  if (line.find_first_of("*!") != std::string::npos) return false;
  if (IsPowerUpText(line)) return true;
  std::istringstream in(line);
  int words = 0;
  for (std::string word; in >> word; ++words) {
    if (!IsCommandWord(word)) return false;
  }
  return words > 0 && line.size() <= 64;
}

}  // namespace irdist::ptu_text
