#pragma once
// The model file's error (estimator/model_file.h), in a header of its own so the model file's
// reader (estimator/model_file_reader.h) and the parts read in their own files throw it without
// including the model file's API.

#include <string>

#include "base/check.h"

namespace irdist {

// A model file that cannot be written, read or understood. what() names the file, the key and,
// when known, the line.
class ModelFileError : public Error {
 public:
  ModelFileError(const std::string& path, const std::string& key, int line,
                 const std::string& problem);
  const std::string& path() const { return path_; }
  const std::string& key() const { return key_; }
  int line() const { return line_; }  // 1-based, 0 when unknown

 private:
  std::string path_;
  std::string key_;
  int line_;
};

}  // namespace irdist
