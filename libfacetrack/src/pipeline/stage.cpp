#include "pipeline/stage.hpp"

namespace facetrack::pipeline {

std::string Fields::names() const {
    static const char* const kNames[] = {"landmarks", "pose", "expression", "identity", "fit", "gaze", "raw", "next start"};
    std::string out;
    for (std::size_t k = 0; k < std::size(kNames); ++k) {
        if (!(bits_ & (1u << k))) continue;
        if (!out.empty()) out += ", ";
        out += kNames[k];
    }
    return out;
}

void provide(const Contract& c, Upstream& upstream) {
    upstream.written = upstream.written | c.writes;
    upstream.expressions.insert(upstream.expressions.end(), c.expressions.begin(), c.expressions.end());
    if (c.expressions_smoothed) {
        upstream.smoothed_expressions.insert(upstream.smoothed_expressions.end(), c.expressions.begin(), c.expressions.end());
    }
}

namespace {

class NotAvailable final : public Stage {
public:
    NotAvailable(const char* name, std::string why) : name_(name), why_(std::move(why)) {}
    StageInfo info() const override { return {name_, false, "not available: " + why_}; }
    Contract contract() const override { return {}; }
    Outcome run(const FrameInput&, FaceTrack&, StageState*) override { return Outcome::Ok; }

private:
    std::string name_, why_;
};

}  // namespace

std::unique_ptr<Stage> notAvailable(const char* name, const std::string& why) { return std::make_unique<NotAvailable>(name, why); }

}  // namespace facetrack::pipeline
