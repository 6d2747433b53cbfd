#pragma once
// What the parts of TsdfVolume share (tsdf_volume.cpp, tsdf_volume_integrate.cpp,
// tsdf_volume_raycast.cpp, tsdf_raycast_gpu.cpp): small helpers on poses and blocks. Not for use elsewhere.

#include "slam/slam_types.h"
#include "slam/tsdf_kernels.h"

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

namespace roomprobe::tsdf_volume_internal {

inline glm::mat3 rotation_matrix(const Pose &p_pose) {
	return glm::mat3(glm::mat3_cast(glm::quat(p_pose.rotation)));
}

inline glm::vec3 block_centre(const glm::ivec3 &p_block, float p_voxel_size) {
	// Voxels 0..7 of a block sit at (8 b + i) voxels; its centre is at 8 b + 3.5.
	return (glm::vec3(p_block) * float(TSDF_BLOCK_SIDE) + glm::vec3(0.5f * float(TSDF_BLOCK_SIDE - 1))) * p_voxel_size;
}

} // namespace roomprobe::tsdf_volume_internal
