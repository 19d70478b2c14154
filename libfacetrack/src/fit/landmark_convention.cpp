#include "fit/landmark_convention.hpp"

#include "core/binary_io.hpp"
#include "fit/fit_basis.hpp"

namespace facetrack::fit {

namespace {
void validate(const LandmarkConvention& c, const std::string& what) {
    if (!c.offsets_frontal_cm.allFinite() || c.offsets_frontal_cm.cwiseAbs().maxCoeff() > 3.0)
        throw Error(what + ": corrupt: offsets not finite or over 3 cm");
}
}  // namespace

void writeLandmarkConvention(const std::string& path, const LandmarkConvention& c) {
    validate(c, "landmark convention for '" + path + "'");
    core::BinaryWriter w;
    w.put<std::uint32_t>(model::kLandmarkCount);
    w.putArray(c.offsets_frontal_cm.data(), static_cast<std::size_t>(c.offsets_frontal_cm.size()));
    core::writeModelFile(path, kConventionMagic, kConventionVersion, w.bytes());
}

LandmarkConvention readLandmarkConvention(const std::string& path) {
    const std::string what = "landmark convention '" + path + "'";
    const std::string payload = core::readModelFile(path, kConventionMagic, kConventionVersion, "landmark convention");
    core::BinaryReader r(payload, what);
    if (r.get<std::uint32_t>() != model::kLandmarkCount) r.fail("landmark count");
    LandmarkConvention c;
    r.getArray(c.offsets_frontal_cm.data(), static_cast<std::size_t>(c.offsets_frontal_cm.size()));
    r.expectEnd();
    validate(c, what);
    return c;
}

void applyConvention(FitBasis& basis, const LandmarkConvention& c) {
    for (int i = 0; i < model::kLandmarkCount; ++i)
        basis.neutral.col(basis.landmark_slots[static_cast<std::size_t>(i)]) += c.offsets_frontal_cm.col(i);
}

}  // namespace facetrack::fit
