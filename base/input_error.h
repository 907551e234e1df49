#pragma once
// The error every reader of an input file throws: it names the file, the line and column (1-based,
// 0 when unknown) and the fix. app/ calls it RecipeError for recipes and rig files.

#include <string>
#include <utility>

#include "base/check.h"

namespace irdist {

// An input file that cannot be used (a recipe, a rig file, a model file, a recording): what is
// wrong, where (file:line:column, 1-based) and what would be valid or what to do.
class InputError : public Error {
 public:
  // line and column are 1-based; 0 when unknown (e.g. the file cannot be opened).
  InputError(std::string file, int line, int column, const std::string& message)
      : Error(Format(file, line, column, message)),
        file_(std::move(file)),
        line_(line),
        column_(column),
        message_(message) {}

  const std::string& File() const { return file_; }
  int Line() const { return line_; }
  int Column() const { return column_; }
  const std::string& Message() const { return message_; }  // without the file:line:column prefix

 private:
  static std::string Format(const std::string& file, int line, int column,
                            const std::string& message) {
    std::string where = file;
    if (line > 0) where += ":" + std::to_string(line);
    if (line > 0 && column > 0) where += ":" + std::to_string(column);
    return where + ": " + message;
  }

  std::string file_;
  int line_;
  int column_;
  std::string message_;
};

}  // namespace irdist
