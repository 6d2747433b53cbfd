#include "dense_mesh_stage.h"

#include <chrono>

namespace roomprobe {

namespace {

double ms_since(std::chrono::steady_clock::time_point p_start) {
	return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - p_start).count();
}

} // namespace

std::shared_ptr<DenseMeshStage::Input> DenseMeshStage::copy_changed(DenseSlam &p_slam) {
	const auto start = std::chrono::steady_clock::now();
	std::vector<TsdfVoxel> storage;
	{
		const std::lock_guard<std::mutex> lock(spare_mutex);
		storage = std::move(spare_storage);
	}
	auto input = std::make_shared<Input>();
	input->blocks = p_slam.copy_changed_blocks(std::move(storage));
	input->copy_ms = ms_since(start);
	return input;
}

std::shared_ptr<DenseMeshSnapshot> DenseMeshStage::mesh(Input &p_input, bool *r_changed) {
	const auto start = std::chrono::steady_clock::now();
	auto snapshot = std::make_shared<DenseMeshSnapshot>();
	const std::lock_guard<std::mutex> lock(mutex);
	*r_changed = mesher.update(p_input.blocks) > 0 || !whole;
	if (*r_changed) {
		whole = std::make_shared<const TriangleMesh>(mesher.mesh());
	}
	// Only the regions the mesher touched are cut again.
	for (auto &[region, triangles] : mesher.region_meshes(DENSE_MESH_REGION_BLOCKS, mesher.changed_regions(DENSE_MESH_REGION_BLOCKS))) {
		if (triangles.indices.empty()) {
			chunks.erase(region);
			continue;
		}
		DenseMeshChunk chunk;
		chunk.region = region;
		chunk.version = ++chunk_versions;
		chunk.mesh = std::make_shared<const TriangleMesh>(std::move(triangles));
		chunks[region] = std::move(chunk);
	}
	snapshot->mesh = whole;
	snapshot->chunks.reserve(chunks.size());
	for (const auto &[region, chunk] : chunks) {
		snapshot->chunks.push_back(chunk);
	}
	snapshot->copy_ms = p_input.copy_ms;
	snapshot->copied_blocks = p_input.blocks.block_count();
	snapshot->mesh_ms = ms_since(start);
	const std::lock_guard<std::mutex> spare_lock(spare_mutex);
	spare_storage = p_input.blocks.release_storage();
	return snapshot;
}

void DenseMeshStage::clear() {
	const std::lock_guard<std::mutex> lock(mutex);
	mesher.clear();
	whole.reset();
	chunks.clear();
}

} // namespace roomprobe
