/// @file image_ops.h
/// @brief Resize / centre-crop RGB-D samples to a training resolution, intrinsics adjusted.
#pragma once

#include "scene/dataset_index.h"
#include "scene/rgbd_sample.h"

namespace p2i::scene {

/// The centre crop that CenterCropResizeSample() takes from a width x height image to reach the
/// aspect ratio of out_width x out_height: the largest such window, centred (x0, y0 rounded down).
cv::Rect CenterCropRect(int width, int height, int out_width, int out_height);

/// Resizes a sample: RGB with area averaging when shrinking (bilinear when growing); depth with
/// nearest neighbour, so no output depth is ever a blend across a depth edge or with an invalid
/// (0) pixel. Pose, stamp and id are kept.
RgbdSample ResizeSample(const RgbdSample& sample, int out_width, int out_height);

/// Centre crop to the target aspect ratio, then resize (e.g. 640x480 -> 480x480 -> 128x128).
RgbdSample CenterCropResizeSample(const RgbdSample& sample, int out_width, int out_height);

/// The calibration matching CenterCropResizeSample(): camera.Cropped(CenterCropRect).Scaled().
CameraInfo CenterCropResizeCamera(const CameraInfo& camera, int out_width, int out_height);

/// Every frame and the camera; throws std::invalid_argument for a non-positive size.
RgbdDataset CenterCropResizeDataset(const RgbdDataset& dataset, int out_width, int out_height);

}  // namespace p2i::scene
