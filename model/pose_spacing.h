/// @file pose_spacing.h
/// @brief How far apart the training poses lie in G's normalised pose input, and the Fourier
/// band count (`fourier_bands: auto`) that spacing calls for. No LibTorch: plain arithmetic.
#pragma once

#include <array>
#include <vector>

namespace p2i::model {

/// The median, over `inputs`, of each one's Euclidean distance to its nearest other input (7-d
/// normalised poses, PoseNormalizer::Normalize). Inputs closer than 1e-9 to each other (the
/// same pose twice) are not each other's neighbour. NaN when fewer than two distinct inputs.
/// O(n^2): 1704 poses (the sim's densest split) take a few milliseconds.
double MedianNeighbourDistance(const std::vector<std::array<float, 7>>& inputs);

/// Band k of the Fourier encoding, sin/cos(2^k pi y), has period 2 / 2^k in the normalised
/// input, so B bands reach a finest period of 2 / 2^(B - 1). `fourier_bands: auto` takes the B
/// whose finest period is nearest, on a log scale, to kAutoBandsPeriodRatio times the median
/// neighbour distance: B = round(1 + log2(2 / (ratio * spacing))), clamped to [1, 16].
/// Bands much finer than the frames' spacing give G features that tell the training frames
/// apart and say nothing between them (docs/MODEL.md "Fourier band count"). The ratio is
/// measured, not derived: 4 chose the best count measured on both the sim (6 bands, above 8)
/// and study-room (4 bands, above 6 and 8); 1 chose 8 and 6 there.
constexpr double kAutoBandsPeriodRatio = 4.0;
/// The band count for `spacing` (MedianNeighbourDistance); throws std::invalid_argument for a
/// spacing that is not finite and positive.
int FourierBandsForSpacing(double spacing);

}  // namespace p2i::model
