#include "model/landmark_convention.hpp"

#include "core/binary_io.hpp"

#include <cmath>

namespace facetrack::model {

namespace {
void validate(const LandmarkConvention& c, const std::string& what) {
    if (!c.offsets_frontal_cm.allFinite() || c.offsets_frontal_cm.cwiseAbs().maxCoeff() > 3.0)
        throw Error(what + ": corrupt: offsets not finite or over 3 cm");
    for (const auto& [name, factor] : c.expression_prior)
        if (!std::isfinite(factor) || !(factor > 0.0) || name.empty()) throw Error(what + ": corrupt expression prior '" + name + "'");
}
}  // namespace

void writeLandmarkConvention(const std::string& path, const LandmarkConvention& c) {
    validate(c, "landmark convention for '" + path + "'");
    core::BinaryWriter w;
    w.put<std::uint32_t>(kLandmarkCount);
    w.putArray(c.offsets_frontal_cm.data(), static_cast<std::size_t>(c.offsets_frontal_cm.size()));
    w.put<std::uint32_t>(static_cast<std::uint32_t>(c.expression_prior.size()));
    for (const auto& [name, factor] : c.expression_prior) {
        w.putString(name);
        w.put<double>(factor);
    }
    core::writeModelFile(path, kConventionMagic, kConventionVersion, w.bytes());
}

LandmarkConvention readLandmarkConvention(const std::string& path) {
    core::ModelFileReader file(path, kConventionMagic, kConventionVersion, kConventionVersion, "landmark convention");
    core::BinaryReader& r = file.reader();
    const std::string& what = file.what();
    if (r.get<std::uint32_t>() != kLandmarkCount) r.fail("landmark count");
    LandmarkConvention c;
    r.getArray(c.offsets_frontal_cm.data(), static_cast<std::size_t>(c.offsets_frontal_cm.size()));
    const auto priors = r.get<std::uint32_t>();
    if (priors > 1000) r.fail("expression prior count");
    for (std::uint32_t k = 0; k < priors; ++k) {
        std::string name = r.getString();
        c.expression_prior[name] = r.get<double>();
    }
    r.expectEnd();
    validate(c, what);
    return c;
}

}  // namespace facetrack::model
