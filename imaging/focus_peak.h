#pragma once
// The peak of a pixel's focus curve between the images of a stack: the vertex of a parabola through the measure
// (or its log, or its power) at the best image and its neighbours, and the part of its uncertainty the curve
// itself shows (its noise). Used by focus_variation.cc.

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "imaging/focus_stack_curves.h"
#include "imaging/focus_variation.h"

namespace fvm::imaging {

// The vertex of the parabola through (z0, f0), (z1, f1), (z2, f2), with f1 the largest; z1 when the three are
// not a maximum (flat or collinear). Stays between z0 and z2.
double Vertex(double z0, double z1, double z2, double f0, double f1, double f2);

// The vertex of the parabola fitted by weighted least squares through the transformed measures P = (f -
// floor)^power (power < 0: P is smallest at the peak) of the best image k of z (mm) and up to two images on
// either side (f[2] the best; NaN or non-positive measures, and images beyond the stack, left out). Each point
// is weighted by (f / f_best)^2, so that a narrow curve is fitted by its top three points, a wide one by five. Stays
// between the best image's neighbours. With `u_noise`, also the vertex's standard deviation for a noise `sigma`
// on each measure (linearised in the transform, summed in quadrature over the points), scaled up by the fit's
// misfit where the points scatter about the parabola more than `sigma` explains (4 or 5 points).
double PowerVertex(const std::vector<double>& z, int k, std::array<double, 5> f, double floor, double power,
                   double sigma = 0.0, double* u_noise = nullptr);

// The exponent p of the measure's fall with the blur sigma s (measure ~ s^-p) for a random texture: the power fit
// transforms the measure by -2 / p, so that the transformed curve grows as s^2.
double BlurExponent(FocusMeasure measure);

// One window's peak at one pixel: the height (mm; NaN where invalid), the noise part of its uncertainty (the
// change of the vertex when each measure moves by its noise: the floor of the curve, the measure far out of
// focus, over the window's side, the sum of window^2 pixels of independent noise), and the quality.
// `model`: how far the vertex moves when the power fit keeps only the best image and its two neighbours (mm; 0
// for the other fits): the focus curve's departure from the fitted parabola near its top, which pulls the vertex
// by a share of the step that depends on where the surface lies between two images and that no noise shows.
struct Peak {
  double z = std::numeric_limits<double>::quiet_NaN();
  double u = std::numeric_limits<double>::quiet_NaN();
  double model = 0.0;
  float quality = 0.0f;
};

// The peak of window curves `c` at pixel i, the images at z (mm); `coarse`: every curve fitted as a narrow one
// (CoarselySampled).
Peak FitPeak(const WindowCurves& c, std::size_t i, const std::vector<double>& z, const FocusVariationOptions& options,
             bool coarse);

// The shoulder of pixel i's focus curve: its best image's two neighbours over the peak, each above the floor (about
// 2 where the steps are far finer than the depth of field, towards 0 where coarser). NaN where the pixel has no
// valid peak (its peak over mean below `min_quality`, or none above the floor) with an image on either side.
float PeakShoulder(const WindowCurves& c, std::size_t i, std::size_t images, double min_quality);

// Whether the stack samples its focus curves more coarsely than their width (see focus_peak.cc).
bool CoarselySampled(const WindowCurves& c, std::size_t images, double min_quality);

}  // namespace fvm::imaging
