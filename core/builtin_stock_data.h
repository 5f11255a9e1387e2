// The built-in stock files, compiled in by CMake from core/stocks/*.json.
#pragma once

#include <vector>

namespace darkroom {

struct BuiltinStockFile {
    const char* file_name;
    const char* json;
};
const std::vector<BuiltinStockFile>& builtin_stock_files();

}  // namespace darkroom
