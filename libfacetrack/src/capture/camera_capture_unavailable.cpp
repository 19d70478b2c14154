// CameraCapture in a build without V4L2 (FACETRACK_WITH_V4L2=OFF): no
// devices, and opening one says why.

#include "facetrack/capture.hpp"

#include "facetrack/error.hpp"

namespace facetrack {

struct CameraCapture::Impl {};

namespace {
[[noreturn]] void unavailable() {
    throw Error(
        "camera capture is not in this build of facetrack (configured with FACETRACK_WITH_V4L2=OFF); "
        "read a clip or images instead");
}
}  // namespace

CameraCapture::CameraCapture(const CaptureSettings&) { unavailable(); }
CameraCapture::CameraCapture(const CaptureSettings&, std::shared_ptr<capture::VideoDevice>) { unavailable(); }
CameraCapture::~CameraCapture() = default;
CameraCapture::CameraCapture(CameraCapture&&) noexcept = default;
CameraCapture& CameraCapture::operator=(CameraCapture&&) noexcept = default;
CaptureStatus CameraCapture::read(CapturedFrame&) { unavailable(); }
const std::string& CameraCapture::device() const { unavailable(); }
int CameraCapture::width() const { unavailable(); }
int CameraCapture::height() const { unavailable(); }
double CameraCapture::fps() const { unavailable(); }
CaptureFormat CameraCapture::format() const { unavailable(); }
std::string CameraCapture::description() const { unavailable(); }
std::vector<std::string> CameraCapture::listDevices() { return {}; }

}  // namespace facetrack
