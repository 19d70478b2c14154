#include "pipeline/stage.hpp"

namespace facetrack::pipeline {

namespace {

class NotAvailable final : public Stage {
public:
    NotAvailable(const char* name, std::string why) : name_(name), why_(std::move(why)) {}
    StageInfo info() const override { return {name_, false, "not available: " + why_}; }
    bool run(const FrameInput&, FaceTrack&, StageState*) override { return true; }

private:
    std::string name_, why_;
};

}  // namespace

std::unique_ptr<Stage> notAvailable(const char* name, const std::string& why) { return std::make_unique<NotAvailable>(name, why); }

}  // namespace facetrack::pipeline
