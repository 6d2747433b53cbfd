#pragma once
// The contact shadow a virtual object casts on the real surface it stands on, by differential
// rendering (Debevec 1998, as the paper's §4.8 and Figure 11 do): over a grid on the supporting
// plane, the ratio of the plane's irradiance with the object to that without it,
//
//   ratio(p) = sum_i L_i T_i(p) / sum_i L_i A_l y_i(n),
//
// where T(p) is the plane point's transfer shadowed by the object (prt_transfer.h, the object as
// the occluder) and the denominator the unshadowed plane's. Multiplying the camera image under
// the object by it darkens the real table as the object would; the probe's SH gives L, so the
// shadow follows the room's light.

#include "prt_transfer.h"

namespace roomprobe {

// A square grid on the plane through p_centre with normal p_normal, p_half_size_m each way,
// p_cells x p_cells quads, with the object's shadowed transfer at every vertex.
struct ShadowCatcher {
	PrtMesh plane; // normals all p_normal
	std::vector<TransferVector> transfer; // one per plane vertex
	std::string error;
};

ShadowCatcher bake_shadow_catcher(const PrtMesh &p_object, const glm::dvec3 &p_centre, const glm::dvec3 &p_normal, double p_half_size_m, int p_cells,
		const TransferOptions &p_options = TransferOptions());

// The ratio at one plane vertex under SH radiance p_radiance (luminance; 1 where nothing shadows,
// 0 where everything does). A sky with no light above the plane gives 1.
double shadow_ratio(const TransferVector &p_transfer, const glm::dvec3 &p_normal, const ShCoefficients &p_radiance);

} // namespace roomprobe
