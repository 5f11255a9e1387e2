// The built-in synthetic scene: a test chart in scene-linear working-space RGB.
#pragma once

#include "core/image.h"

namespace darkroom {

// Bands from top to bottom: a smooth grey ramp (-8 to +4 stops around 0.18), a step
// wedge (21 steps, half a stop apart), fine detail (sine bursts of rising frequency and a
// Siemens star) and a 24-patch colour chart.
Image demo_scene(int width = 1536, int height = 1024);

}  // namespace darkroom
