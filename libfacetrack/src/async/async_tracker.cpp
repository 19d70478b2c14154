// AsyncTracker: a reading thread hands the newest frame to a tracking thread
// through a one-frame slot (a newer frame replaces one not taken yet: dropped),
// and the tracking thread publishes each result in a latest-value slot.
// Buffers are swapped, not queued: memory stays what one frame and two results take.

#include "facetrack/async_tracker.hpp"

#include "facetrack/error.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

namespace facetrack {

namespace {
using Clock = std::chrono::steady_clock;

/// A frame's pixels copied out of the source's buffer, rows packed.
struct FrameCopy {
    std::vector<std::uint8_t> pixels;
    ImageView view;
    long number = 0;
    double time_s = 0.0;
    Clock::time_point arrival;

    void assign(const ImageView& from) {
        const std::size_t row = static_cast<std::size_t>(from.width) * static_cast<std::size_t>(bytesPerPixel(from.format));
        if (!from.data || from.width <= 0 || from.height <= 0 || from.stride < row) throw Error("the source gave an invalid frame");
        pixels.resize(row * static_cast<std::size_t>(from.height));
        for (int y = 0; y < from.height; ++y) std::memcpy(pixels.data() + y * row, from.data + y * from.stride, row);
        view = {pixels.data(), from.width, from.height, row, from.format};
    }
};
}  // namespace

struct AsyncTracker::Impl {
    Impl(Models models, const TrackerConfig& config, std::unique_ptr<FrameSource> s, const AsyncOptions& o)
        : tracker(std::move(models), config), source(std::move(s)), options(o) {
        tracker.setCalibration(options.calibration);
        in_use = options.calibration;
    }

    Tracker tracker;
    std::unique_ptr<FrameSource> source;
    AsyncOptions options;

    // Reading -> tracking.
    std::mutex frame_mutex;
    std::condition_variable frame_ready, frame_taken;
    FrameCopy pending, working;
    bool has_pending = false, reading_done = false, stopping = false;
    long frames_read = 0, frames_dropped = 0;
    std::string read_error;

    // Tracking -> the application.
    mutable std::mutex result_mutex;
    mutable std::condition_variable result_ready;
    AsyncResult published, next;
    long frames_tracked = 0;
    double latency_sum_ms = 0.0;
    bool finished = false;
    std::string track_error;

    // The application -> tracking: calibration requests, applied before the next frame.
    mutable std::mutex calibration_mutex;
    std::optional<Calibration> requested;
    bool neutral_requested = false;
    Calibration in_use;            ///< as of the last frame: what calibration() returns
    bool identity_in_use = false;  ///< the last frame's first face had its identity estimated

    std::thread reader, worker;

    void read();
    void track();
    /// Before a frame: the requests taken and applied, in_use refreshed when they changed it.
    void applyCalibrationRequests();
    /// After a frame: in_use refreshed when the first face's identity was just estimated.
    void noteIdentity(const FrameResult& result);
};

void AsyncTracker::Impl::applyCalibrationRequests() {
    std::optional<Calibration> given;
    bool neutral = false;
    {
        std::lock_guard<std::mutex> lock(calibration_mutex);
        if (!requested && !neutral_requested) return;
        given.swap(requested);
        neutral = std::exchange(neutral_requested, false);
    }
    if (given) tracker.setCalibration(*given);  // checked when it was requested
    if (neutral) tracker.calibrateNeutral();
    Calibration now = tracker.calibration();
    std::lock_guard<std::mutex> lock(calibration_mutex);
    in_use = std::move(now);
}

void AsyncTracker::Impl::noteIdentity(const FrameResult& result) {
    // Kept when the face is lost: a profile saved then still has the user's identity.
    const bool estimated = !result.faces.empty() && result.faces.front().identity_calibrated;
    const bool fresh = estimated && !identity_in_use;
    identity_in_use = estimated;
    if (!fresh) return;
    Calibration now = tracker.calibration();
    std::lock_guard<std::mutex> lock(calibration_mutex);
    in_use = std::move(now);
}

void AsyncTracker::Impl::read() {
    const bool paced = !source->live() && options.realtime;
    const bool waitForTracker = !source->live() && !options.realtime;
    Clock::time_point start;
    double firstTime = 0.0;
    std::string error;
    for (long number = 0;;) {
        ImageView view;
        double time_s = 0.0;
        FrameSource::Status status;
        try {
            status = source->read(view, time_s);
        } catch (const std::exception& e) {
            error = e.what();
            break;
        }
        if (status == FrameSource::Status::Timeout) {
            std::lock_guard<std::mutex> lock(frame_mutex);
            if (stopping) break;
            continue;
        }
        if (status == FrameSource::Status::Disconnected) error = source->describe() + ": the camera went away";
        if (status != FrameSource::Status::Frame) break;

        std::unique_lock<std::mutex> lock(frame_mutex);
        if (paced) {
            // A clip plays at its own rate: frame n is due at its timestamp after the first.
            if (number == 0) start = Clock::now(), firstTime = time_s;
            const auto due = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time_s - firstTime));
            frame_taken.wait_until(lock, due, [&] { return stopping; });
        }
        if (waitForTracker) frame_taken.wait(lock, [&] { return !has_pending || stopping; });
        if (stopping) break;
        if (has_pending) ++frames_dropped;
        try {
            pending.assign(view);
        } catch (const std::exception& e) {
            error = e.what();
            break;
        }
        pending.number = number++;
        pending.time_s = time_s;
        pending.arrival = Clock::now();
        has_pending = true;
        ++frames_read;
        lock.unlock();
        frame_ready.notify_one();
    }
    std::lock_guard<std::mutex> lock(frame_mutex);
    reading_done = true;
    read_error = error;
    frame_ready.notify_one();
}

void AsyncTracker::Impl::track() {
    std::string error;
    for (;;) {
        {
            std::unique_lock<std::mutex> lock(frame_mutex);
            frame_ready.wait(lock, [&] { return has_pending || reading_done || stopping; });
            if (stopping || !has_pending) break;
            std::swap(pending, working);
            has_pending = false;
        }
        frame_taken.notify_one();
        try {
            if (source->separateScenes()) tracker.reset();
            applyCalibrationRequests();
            tracker.process(working.view, working.time_s, next.result);
            noteIdentity(next.result);
        } catch (const std::exception& e) {
            error = e.what();
            break;
        }
        next.frame_number = working.number;
        next.time_s = working.time_s;
        next.arrival = working.arrival;
        next.latency_ms = std::chrono::duration<double, std::milli>(Clock::now() - working.arrival).count();
        {
            std::lock_guard<std::mutex> lock(result_mutex);
            std::swap(published, next);
            ++frames_tracked;
            latency_sum_ms += published.latency_ms;
        }
        result_ready.notify_all();
    }
    {
        std::lock_guard<std::mutex> lock(frame_mutex);
        stopping = true;  // the reader stops too when tracking failed
    }
    frame_taken.notify_all();
    {
        std::lock_guard<std::mutex> lock(result_mutex);
        track_error = error;
        finished = true;
    }
    result_ready.notify_all();
}

AsyncTracker::AsyncTracker(Models models, const TrackerConfig& config, std::unique_ptr<FrameSource> source, const AsyncOptions& options) {
    if (!source) throw Error("AsyncTracker: no frame source");
    impl_ = std::make_unique<Impl>(std::move(models), config, std::move(source), options);
    impl_->reader = std::thread([this] { impl_->read(); });
    impl_->worker = std::thread([this] { impl_->track(); });
}

AsyncTracker::~AsyncTracker() { stop(); }

void AsyncTracker::stop() {
    {
        std::lock_guard<std::mutex> lock(impl_->frame_mutex);
        impl_->stopping = true;
    }
    impl_->frame_ready.notify_all();
    impl_->frame_taken.notify_all();
    if (impl_->reader.joinable()) impl_->reader.join();
    if (impl_->worker.joinable()) impl_->worker.join();
}

void AsyncTracker::setCalibration(const Calibration& calibration) {
    validate(calibration, *impl_->tracker.models().face);  // the models are immutable: safe from any thread
    std::lock_guard<std::mutex> lock(impl_->calibration_mutex);
    impl_->requested = calibration;
}

void AsyncTracker::calibrateNeutral() {
    std::lock_guard<std::mutex> lock(impl_->calibration_mutex);
    impl_->neutral_requested = true;
}

Calibration AsyncTracker::calibration() const {
    std::lock_guard<std::mutex> lock(impl_->calibration_mutex);
    return impl_->in_use;
}

bool AsyncTracker::latest(AsyncResult& out) const {
    std::lock_guard<std::mutex> lock(impl_->result_mutex);
    if (impl_->published.frame_number < 0 || impl_->published.frame_number <= out.frame_number) return false;
    out = impl_->published;
    return true;
}

bool AsyncTracker::waitForNewer(AsyncResult& out, double timeout_s) const {
    std::unique_lock<std::mutex> lock(impl_->result_mutex);
    const auto newer = [&] { return impl_->published.frame_number > out.frame_number; };
    impl_->result_ready.wait_for(lock, std::chrono::duration<double>(std::max(0.0, timeout_s)), [&] { return newer() || impl_->finished; });
    if (!newer()) return false;
    out = impl_->published;
    return true;
}

AsyncStats AsyncTracker::stats() const {
    AsyncStats s;
    {
        std::lock_guard<std::mutex> lock(impl_->frame_mutex);
        s.frames_read = impl_->frames_read;
        s.frames_dropped = impl_->frames_dropped;
        s.error = impl_->read_error;
    }
    std::lock_guard<std::mutex> lock(impl_->result_mutex);
    s.frames_tracked = impl_->frames_tracked;
    s.mean_latency_ms = impl_->frames_tracked > 0 ? impl_->latency_sum_ms / static_cast<double>(impl_->frames_tracked) : 0.0;
    s.finished = impl_->finished;
    if (!impl_->track_error.empty()) s.error = impl_->track_error;
    return s;
}

}  // namespace facetrack
