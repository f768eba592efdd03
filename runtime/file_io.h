#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace shapesense {

// Whole-file reads and writes. Errors are InputError naming the path.
std::string ReadTextFile(const std::filesystem::path& path);

// Writes via a temporary file and a rename, so a reader never sees a half
// file and a failure leaves no broken output behind.
void WriteFileAtomically(const std::filesystem::path& path, const std::string& contents);

// Reads an 8-bit BGR image; InputError naming the path when it is missing,
// unreadable, or not 8-bit colour (grey images are converted).
cv::Mat ReadBgrImage(const std::filesystem::path& path);

void WritePng(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace shapesense
