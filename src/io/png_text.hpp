#pragma once
#include <string>
#include <utility>
#include <vector>

namespace ps::io {

// Inserts tEXt chunks right after a PNG's IHDR chunk (OpenCV's encoder cannot write them).
// Throws std::invalid_argument if `png` is not a PNG stream.
std::vector<unsigned char> addPngTextChunks(
    const std::vector<unsigned char>& png,
    const std::vector<std::pair<std::string, std::string>>& entries);

// Reads all tEXt chunks of a PNG stream.
std::vector<std::pair<std::string, std::string>> readPngTextChunks(
    const std::vector<unsigned char>& png);

}  // namespace ps::io
