#pragma once
// The PNG files snap and view write (snap's frame and preview, view's screenshots): checked before
// the camera starts, then written whole.

#include <opencv2/core.hpp>
#include <string>

namespace irdist {

// An output image named by `flag`: a .png (the only format that keeps 16-bit values), not an
// existing file unless `force`, never a symbolic link, in a folder that exists and can be written.
// Throws UsageError (another format) or RunFolderError. Checked before the camera starts.
void CheckPngOutput(const std::string& path, bool force, const char* flag);

// `image` as a PNG at `path`, written whole (a temporary file renamed into place); throws
// RunFolderError naming `what` when it cannot be.
void WritePng(const std::string& path, const cv::Mat& image, const char* what);

}  // namespace irdist
