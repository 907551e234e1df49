#pragma once
// The inter-pixel crosstalk's kernel on the pixel grid, the part of the blur that comes after the
// pixels sample the image (blob_fit.h Crosstalk): a sampled Gaussian convolved with a lattice
// random walk (charge hopping between neighbours, e^-t I_n(t)), normalised, 1-D (applied along x,
// then y).

#include <vector>

namespace irdist {

// The kernel of variance crosstalk_var_px2 on the grid of which lattice_share (clamped to [0, 1])
// is spread as the lattice walk, the rest as the sampled Gaussian of that variance (its sd found
// by bisection: at small variances a sampled Gaussian's variance falls below sd^2); outer taps
// below 1e-7 dropped (1e-7 of the amplitude: 0.007 DN at a 16-bit full scale; a small
// crosstalk's sampled Gaussian reaches 3 px for taps of 1e-11 and less), then normalised again.
// Odd length, sums to 1; {1} for no crosstalk. The last kernel is kept per thread (a model's
// crosstalk is one kernel for every frame; the bisection and the Bessel terms cost 20 us): the
// reference stays valid until the thread's next call with other arguments.
const std::vector<double>& CrosstalkKernel(double crosstalk_var_px2, double lattice_share);

}  // namespace irdist
