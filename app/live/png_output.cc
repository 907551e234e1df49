#include "app/live/png_output.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string_view>
#include <vector>

#include "app/inputs/errors.h"
#include "base/safe_file.h"

namespace irdist {

namespace fs = std::filesystem;

void CheckPngOutput(const std::string& path, bool force, const char* flag) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension != ".png") {
    throw UsageError(std::string(flag) + " " + path + ": irdist writes PNG images only (the one "
                     "supported format: .png, which keeps every bit of the frame); name the "
                     "file FILE.png.");
  }
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(path, ec);
  if (fs::is_symlink(status)) {
    throw RunFolderError(path + " is a symbolic link; irdist never writes through one. Remove it "
                         "or choose another " + flag + " name.");
  }
  if (fs::exists(status) && !force) {
    throw RunFolderError(path + " exists: irdist does not replace a file unasked. Choose another " +
                         std::string(flag) + " name, or add --force to replace it.");
  }
  // The folder is checked now, before the camera starts or the station moves.
  const fs::path parent = fs::path(path).has_parent_path() ? fs::path(path).parent_path() : ".";
  if (!fs::is_directory(parent, ec)) {
    throw RunFolderError(std::string(flag) + " " + path + ": the folder " + parent.string() +
                         " does not exist (or is not a folder); create it first or choose "
                         "another " + flag + ".");
  }
  if (::access(parent.c_str(), W_OK) != 0) {
    throw RunFolderError(std::string(flag) + " " + path + ": cannot write in " + parent.string() +
                         " (" + std::strerror(errno) + "); choose another " + flag + ".");
  }
}

void WritePng(const std::string& path, const cv::Mat& image, const char* what) {
  std::vector<uchar> png;
  std::string why = "cannot be encoded as PNG";
  if (!cv::imencode(".png", image, png) ||
      !WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(png.data()),
                                                  png.size()), 0644, &why)) {
    throw RunFolderError(path + ": cannot write the " + what + ": " + why + "; check the folder.");
  }
}

}  // namespace irdist
