#pragma once
// The round-blob rule on a bracket's frames together (docs/estimator.md "A round blob's size").
// Every frame of a bracket images the same disc: the blob fit's anisotropy of P (px^-2) is the
// same in each, with its own noise (a short reference frame's larger). One frame's evidence leaves
// a round blob and a slightly tilted one close (a round blob's t = |a|^2 / E|a_noise|^2 is
// exponential of mean 1, a 5 deg blob's at 2 m near 7.5), so a rare round frame read as a 4 deg
// ellipse, 6 mm short; the frames together put the decision on the bracket's whole signal.

#include <vector>

#include "estimator/features.h"

namespace irdist {

// The pooled rule's t0 and k (psf_anisotropy.h DenoisedAnisotropy2): later and gentler than one
// frame's (6 and 2). A round blob's pooled t is exponential of mean 1 as one frame's is, but a
// real ellipse's t grows with the bracket's signal (the virtual rig's 5 deg at 2 m: ~7.5 in one
// 33 ms frame, ~22 in a bracket of 8 + 30..36 ms), so the rule can wait longer: a round blob reads
// theta > 2 deg beyond t ~ 7 (0.1% of brackets; one frame's rule: 1%), 10-30 deg keep their |a|^2
// whole, and the 5 deg blob of a whole bracket still does (a pair of 8 + 35 ms gains only 1.2x:
// there a 5 deg blob reads low, as one frame did under t0 = 12).
constexpr double kPooledRoundRuleMidpoint = 10.0;
constexpr double kPooledRoundRuleSlope = 1.0;

// The frames' anisotropy pooled: each frame's fitted a = ((P11 - P22) / 2, P12) weighted by its
// inverse noise, the pool's noise 1 / sum(1 / noise), and the round-blob rule
// (DenoisedAnisotropy2 with the pooled t0 and k) applied to the pool. Each frame then carries the
// pool's |a| in place of its own rule's: its trace, its axes' direction and any change made since
// the fit (the line of sight, a refocused blur) kept. Frames without the blob fit's anisotropy and
// its noise (the moments' path) are left as they are, and so is every frame when fewer than two
// have them.
void PoolRoundBlobRule(std::vector<Features*> frames);

// The rule pooled over a bracket's reference and measurements, in place.
void PoolBracket(Features* reference, std::vector<Features>* measurements);

}  // namespace irdist
