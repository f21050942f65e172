#include "core/refinement.h"

#include <bit>
#include <algorithm>
#include <cmath>

namespace vkmesh {

bool isRegularType(int t) {
    for (uint8_t r : kRegularTypes)
        if (t == int(r)) return true;
    return false;
}

int refineType(int prev, int t, const float d[8], float epsilon) {
    if (t == 0 || t == 255 || isRegularType(t)) return t;
    if (std::popcount(unsigned(prev ^ t) & 0xFFu) > 3) return t;
    int best = t;
    float bestSum = 0.0f;
    bool found = false;
    for (uint8_t r : kRegularTypes) {
        const unsigned flipped = unsigned(r ^ t) & 0xFFu;
        if (std::popcount(flipped) > 3) continue;
        bool ok = true;
        float sum = 0.0f;
        for (int i = 0; i < 8; ++i) {
            if (!((flipped >> i) & 1u)) continue;
            const float a = std::fabs(d[i]);
            if (!(a < epsilon)) {
                ok = false;
                break;
            }
            sum += a;
        }
        if (!ok) continue;
        if (!found || sum < bestSum) {  // strict: a tie keeps the earlier regular type
            best = r;
            bestSum = sum;
            found = true;
        }
    }
    return best;
}

}  // namespace vkmesh

namespace vkmesh {

int regularDistance(int t) {
    int best = std::min(std::popcount(unsigned(t) & 0xFFu), std::popcount(~unsigned(t) & 0xFFu));
    for (uint8_t r : kRegularTypes) best = std::min(best, std::popcount(unsigned(r ^ t) & 0xFFu));
    return best;
}

int refinedCubeType(const float d[kWindowSize], const bool observed[kWindowSize], float epsilon) {
    // Raw types of the 27 cubes whose corner 0 lies at window offsets -1..1 (index i + 3 j + 9 k), -1 when a
    // corner is unobserved (such a cube has no surface whatever its signs).
    int raw[27];
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j)
            for (int i = 0; i < 3; ++i) {
                int t = 0;
                bool seen = true;
                for (int c = 0; c < 8; ++c) {
                    const int w = windowIndex(i - 1 + (c & 1), j - 1 + ((c >> 1) & 1), k - 1 + ((c >> 2) & 1));
                    seen = seen && observed[w];
                    if (d[w] < 0.0f) t |= 1 << c;
                }
                raw[i + 3 * j + 9 * k] = seen ? t : -1;
            }
    if (raw[13] < 0) return 0;  // the cube itself is not observed
    int type = 0;
    for (int c = 0; c < 8; ++c) {
        const int x = c & 1, y = (c >> 1) & 1, z = (c >> 2) & 1;
        bool inside = (raw[13] >> c) & 1;
        if (std::fabs(d[windowIndex(x, y, z)]) < epsilon) {
            // The 8 cubes around the corner: corner 0 at (x, y, z) - o, the corner is their corner o.
            // Decided only with all 8 observed: at the rim of the observed surface a flip would move the rim.
            int keep = 0, flip = 0;
            bool all8 = true;
            for (int o = 0; o < 8; ++o) {
                const int t = raw[(x - (o & 1) + 1) + 3 * (y - ((o >> 1) & 1) + 1) + 9 * (z - ((o >> 2) & 1) + 1)];
                if (t < 0) {
                    all8 = false;
                    break;
                }
                keep += regularDistance(t);
                flip += regularDistance(t ^ (1 << o));
            }
            if (all8 && flip < keep) inside = !inside;
        }
        if (inside) type |= 1 << c;
    }
    return type;
}

}  // namespace vkmesh
