#include "core/refinement.h"

#include <bit>
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
