#pragma once

// Internal to RegionFusion (core/src/dynamic/region_fusion.cpp): one object's state from frame
// to frame.

#include "dynamap/core/dynamic/object_tracks.hpp"
#include "dynamap/core/dynamic/region_fusion.hpp"
#include "dynamap/core/dynamic_config.hpp"

namespace dynamap {

/// Anchored points needed for the anchor test (and to find a track by its points).
constexpr int kAnchorMinPoints = 3;

/// The transition of one object's state: decides `d` (moving_now, motion_now, unconfirmed,
/// moving, quiet_frames) given its track in the last frame (null: new object) and this frame's
/// evidence; returns its new track. `high_dynamic`: its class moves by itself (a person), and
/// keeping it takes evidence gathered over time.
ObjectTrack nextObjectState(ObjectDecision& d, const ObjectTrack* prev,
                            const FusionEvidence& evidence, const DynamicConfig& config,
                            bool high_dynamic);

}  // namespace dynamap
