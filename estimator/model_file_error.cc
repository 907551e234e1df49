#include "estimator/model_file_error.h"

#include <sstream>

namespace irdist {
namespace {

std::string Message(const std::string& path, const std::string& key, int line,
                    const std::string& problem) {
  std::ostringstream out;
  out << "model file " << path;
  if (line > 0) out << ":" << line;
  if (!key.empty()) out << ": key '" << key << "'";
  out << ": " << problem << ". Re-run the calibration (irdist fit) to write a valid model file.";
  return out.str();
}

}  // namespace

ModelFileError::ModelFileError(const std::string& path, const std::string& key, int line,
                               const std::string& problem)
    : Error(Message(path, key, line, problem)), path_(path), key_(key), line_(line) {}

}  // namespace irdist
