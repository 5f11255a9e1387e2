// Reading the JSON files a user names (stocks, look files, grain profiles) with one size
// limit, checked before the file is read: nlohmann-json holds a parsed document in some 17
// times its text, so a 200 MB file would take gigabytes before any field is checked.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace darkroom {

// The largest such file read: the built-in stocks are under 100 KB each, a look file or a
// grain profile a few KB.
inline constexpr std::uintmax_t kMaxJsonFileBytes = 16u << 20;

// The text of the file at `path`, a `kind` ("stock file"); throws Error naming the file when
// it cannot be opened or is larger than kMaxJsonFileBytes.
template <typename Error>
std::string read_json_file(const std::string& path, const std::string& kind) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error(path + ": cannot open " + kind);
    std::error_code ec;
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (!ec && bytes > kMaxJsonFileBytes)
        throw Error(path + ": the " + kind + " is " + std::to_string(bytes >> 20) + " MB, more than the " +
                    std::to_string(kMaxJsonFileBytes >> 20) + " MB a " + kind + " may be");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

}  // namespace darkroom
