// Running the darkroom program from tests: its exit status and output, input images, pixels.
#pragma once

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

namespace darkroom_test {

namespace fs = std::filesystem;

struct Result {
    int exit_code;
    std::string output;  // stdout and stderr together
};

inline const fs::path kTmp = DARKROOM_TEST_TMP;

// Runs a shell command line, capturing what it prints.
inline Result shell(const std::string& command) {
    fs::create_directories(kTmp);
    fs::path log = kTmp / ("output-" + std::to_string(std::hash<std::string>{}(command)) + ".txt");
    std::string cmd = command + " > " + log.string() + " 2>&1";
    int status = std::system(cmd.c_str());
    std::ifstream in(log);
    std::stringstream text;
    text << in.rdbuf();
    return {WEXITSTATUS(status), text.str()};
}

inline Result darkroom(const std::string& args) { return shell(std::string(DARKROOM_EXE) + " " + args); }

inline std::string make_input(const std::string& name, int w = 64, int h = 48) {
    fs::create_directories(kTmp);
    std::string path = (kTmp / name).string();
    OIIO::ImageBuf buf(OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::FLOAT));
    const float top[3] = {0.02f, 0.05f, 0.1f}, bottom[3] = {1.5f, 0.9f, 0.3f};
    OIIO::ImageBufAlgo::fill(buf, top, bottom);
    REQUIRE(buf.write(path));
    return path;
}

inline std::vector<float> pixels(const std::string& path, OIIO::ImageSpec* spec = nullptr) {
    OIIO::ImageBuf buf(path);
    REQUIRE(buf.read(0, 0, true, OIIO::TypeDesc::FLOAT));
    if (spec) *spec = buf.spec();
    std::vector<float> out(buf.spec().image_pixels() * buf.nchannels());
    buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, out.data());
    return out;
}

inline std::string file_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    return bytes.str();
}

// The hidden temporaries a run leaves in `dir` (see cli/atomic_file.h).
inline int temp_files_in(const fs::path& dir) {
    int n = 0;
    for (auto& entry : fs::directory_iterator(dir)) n += entry.path().filename().string().rfind(".darkroom-tmp", 0) == 0;
    return n;
}

}  // namespace darkroom_test
