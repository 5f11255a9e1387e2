// Develops a grey ramp through a built-in film and paper with the installed core, and prints
// the print's values: they must rise with the exposure.
#include <cstdio>

#include "core/develop.h"
#include "core/stock.h"

int main() {
    const int width = 8;
    darkroom::Image scene(width, 1, 3);
    for (int x = 0; x < width; ++x)
        for (int c = 0; c < 3; ++c) scene.at(x, 0)[c] = 0.18f * float(1 << x) / 16.0f;
    darkroom::DevelopSettings settings;
    settings.grain = false;
    const darkroom::Stock film = darkroom::find_stock("kodak-vision3-250d"), paper = darkroom::find_stock("kodak-2383");
    const darkroom::Plan plan = darkroom::Plan::compile(film, &paper, settings, darkroom::FrameGeometry{width, 1});
    darkroom::Image print(scene.window, 3);
    plan.run(scene.view(), print.view(), 1);
    for (int x = 0; x < width; ++x) std::printf("%.6f\n", print.at(x, 0)[1]);
    return 0;
}
