#pragma once
/// \file
/// Tracking on its own thread, for applications whose loop must never wait on
/// it (a game's render loop): the AsyncTracker owns a frame source (a webcam,
/// a clip, a folder of images) and a Tracker, and keeps the newest result in a
/// latest-value slot that the application reads whenever it likes.
///
///     facetrack::AsyncTracker tracking(facetrack::Models::loadDefault(), {},
///                                      facetrack::openCameraSource({"/dev/video0"}));
///     facetrack::AsyncResult latest;
///     while (running) {                           // the render loop
///         if (tracking.latest(latest)) { /* a newer frame's faces: latest.result */ }
///         render();
///     }
///
/// Threads: the AsyncTracker runs two threads of its own, one reading frames
/// and one tracking; latest() and stats() may be called from any thread and
/// only copy under a lock held for a swap. Nothing queues up: a frame that
/// arrives while the previous one still waits to be tracked replaces it and
/// counts as dropped.

#include "facetrack/calibration.hpp"
#include "facetrack/capture.hpp"
#include "facetrack/image.hpp"
#include "facetrack/result.hpp"
#include "facetrack/tracker.hpp"

#include <chrono>
#include <memory>
#include <string>

namespace facetrack {

/// Where an AsyncTracker's frames come from.
class FrameSource {
public:
    enum class Status { Frame, Timeout, End, Disconnected };
    virtual ~FrameSource() = default;
    /// The next frame; `frame` stays valid until the next call. time_s: its
    /// timestamp (a clip's frame time, a camera's capture time). Called from
    /// the AsyncTracker's reading thread only.
    virtual Status read(ImageView& frame, double& time_s) = 0;
    /// True for cameras: frames come at their own rate, whatever the reader does.
    virtual bool live() const = 0;
    /// True when every frame is its own scene (a folder of photos): the
    /// tracker starts afresh for each.
    virtual bool separateScenes() const = 0;
    virtual std::string describe() const = 0;
};

/// A V4L2 webcam (CameraCapture). Throws Error when it cannot be opened.
std::unique_ptr<FrameSource> openCameraSource(const CaptureSettings& settings);
/// A video clip, one image, or a folder of images (sorted by name, each its
/// own scene, 1 s apart). Throws Error when the path is none of these.
std::unique_ptr<FrameSource> openMediaSource(const std::string& path);

struct AsyncOptions {
    /// For files: play at the clip's own rate, dropping frames the tracker is
    /// too slow for, as a camera would (true); or track every frame as fast as
    /// possible, the reader waiting for the tracker (false). Cameras always
    /// run at their own rate.
    bool realtime = true;
    /// The user's calibration, applied before the first frame (Tracker::setCalibration).
    Calibration calibration;
};

/// One tracked frame, as latest() hands it over.
struct AsyncResult {
    FrameResult result;
    long frame_number = -1;   ///< frames read from the source before this one (0 is the first)
    double time_s = 0.0;      ///< the frame's timestamp from the source
    double latency_ms = 0.0;  ///< from the frame's arrival (read returning) to its result being ready
    /// When the frame arrived, for timing what the application does with the
    /// result afterwards (a sender's capture-to-packet latency).
    std::chrono::steady_clock::time_point arrival;
};

struct AsyncStats {
    long frames_read = 0;
    long frames_tracked = 0;
    long frames_dropped = 0;  ///< read but replaced by a newer frame before the tracker took them
    double mean_latency_ms = 0.0;
    bool finished = false;  ///< the source ended (or failed: see error), nothing more will come
    std::string error;      ///< why the source or the tracker stopped, if they failed
};

class AsyncTracker {
public:
    /// Starts reading and tracking at once. Throws Error when the Tracker
    /// cannot be set up or `source` is null.
    AsyncTracker(Models models, const TrackerConfig& config, std::unique_ptr<FrameSource> source, const AsyncOptions& options = {});
    /// Stops both threads (waiting at most for the source's read timeout).
    ~AsyncTracker();
    AsyncTracker(const AsyncTracker&) = delete;
    AsyncTracker& operator=(const AsyncTracker&) = delete;

    /// Copies the newest result into `out` when it is newer than the one `out`
    /// holds (by frame_number) and returns true; false when there is nothing
    /// newer. Never waits for tracking; reuses `out`'s memory.
    bool latest(AsyncResult& out) const;
    /// latest(), waiting up to `timeout_s` for a newer result: for a consumer
    /// thread that acts on every result (a network sender), not a render loop.
    /// Returns false on timeout or once tracking has finished with nothing newer.
    bool waitForNewer(AsyncResult& out, double timeout_s) const;
    AsyncStats stats() const;

    /// The user's calibration (Tracker::setCalibration), checked now (Error on a
    /// bad value or size; nothing changes) and applied by the tracking thread
    /// before its next frame.
    void setCalibration(const Calibration& calibration);
    /// Tracker::calibrateNeutral() before the next frame: the neutral of the
    /// first face as last tracked (ask the user to relax first).
    void calibrateNeutral();
    /// The calibration in use as of the last tracked frame, with the identity
    /// once estimated (Tracker::calibration); a request not yet applied is not in it.
    Calibration calibration() const;

    /// Stops reading and tracking; later calls do nothing. latest() keeps the last result.
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace facetrack
