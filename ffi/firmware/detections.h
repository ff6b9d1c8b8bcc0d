/* Detections scored by the C example on the emulated Cortex-M4F and, for the
 * expected values, by the host library: the first 24 rows of examples/data/test.csv
 * (car, cyclist, pedestrian logits, objectness) and a few edge cases. */
#ifndef DETECTIONS_H
#define DETECTIONS_H

#include <math.h>

#define N_DETECTIONS 32

/* Heads scored for each detection: ML, MAP, Bayes, open. */
#define N_HEADS 4

static const float detections[N_DETECTIONS][4] = {
    {2.6283f, -3.7759f, -3.7148f, 0.6091f},
    {-1.5155f, -2.1577f, 4.7103f, 0.7606f},
    {-4.5564f, 4.2786f, 1.5954f, 0.9668f},
    {-5.2637f, 2.7016f, -3.6420f, 0.8178f},
    {1.6454f, -4.9396f, -3.7251f, 0.8827f},
    {1.5308f, -2.0375f, -4.4045f, 0.9384f},
    {3.9984f, -4.2986f, -3.7070f, 0.3099f},
    {-2.3733f, -3.8130f, 3.9806f, 0.8863f},
    {3.4216f, -3.4924f, -3.6607f, 0.6750f},
    {4.2784f, -2.2393f, -2.6890f, 0.7741f},
    {4.4131f, -2.9186f, -5.1224f, 0.9002f},
    {5.8360f, -1.8900f, -3.0412f, 0.8762f},
    {4.4407f, -3.1612f, -3.4020f, 0.7329f},
    {-4.7499f, -6.6110f, 2.7963f, 0.8177f},
    {4.0221f, -3.7995f, -4.6135f, 0.9311f},
    {4.5637f, -3.9038f, -3.6030f, 0.8961f},
    {-1.8534f, 0.2457f, -4.9851f, 0.9160f},
    {-1.0234f, -3.1679f, -2.3721f, 0.7391f},
    {2.6917f, -2.4963f, -3.2197f, 0.9393f},
    {2.9695f, -1.2599f, -5.0518f, 0.5308f},
    {-2.8216f, 4.3120f, 2.8665f, 0.8758f},
    {4.3198f, -5.3174f, -5.6301f, 0.7797f},
    {4.9635f, -4.9316f, -2.4347f, 0.9578f},
    {0.3371f, -1.8213f, -2.6587f, 0.7074f},
    {INFINITY, -INFINITY, 0.0f, 1.0f},
    {1e30f, -1e30f, 3.0f, 0.5f},
    {0.0f, 0.0f, 0.0f, 0.0f},
    {50.0f, -50.0f, 50.0f, 0.9f},
    {-3.0f, -3.0f, -3.0f, 1.0f},
    {5.1f, -2.0f, -1.3f, 0.93f},
    {-1.0f, 3.2f, -0.5f, 1.0f},
    {2.0f, 2.0f, 2.0f, 0.25f},
};

#endif
