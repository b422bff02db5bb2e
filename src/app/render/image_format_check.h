#pragma once
// The render command's check that its images can be written, run beside the render.
#include "candela/app/cli.h"

#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace candela::app {

/// Checks that every image's format writes (check_image_format() on render_images()) on a
/// thread of its own, which loads the image module on the way: OpenImageIO's libraries take a
/// few tenths of a second of processor time to load, and this way the load overlaps the render
/// instead of coming before it. The thread starts at once but loads nothing before start(): the
/// dynamic loader holds a lock for the whole load that every new thread of the process needs
/// (for its thread-local storage), so the load must begin only once the render's threads (TBB's
/// workers, the progress and interrupt threads) are running, i.e. after its first pass. A
/// failure stops the render at the next pass (stop_on_failure()) and finish() throws it, before
/// anything is written.
class ImageFormatCheck {
  public:
    explicit ImageFormatCheck(std::vector<RenderImage> images);
    /// A check not started by then is dropped (the render failed: no image will be written).
    ~ImageFormatCheck();
    ImageFormatCheck(const ImageFormatCheck&) = delete;
    ImageFormatCheck& operator=(const ImageFormatCheck&) = delete;

    /// Lets the check begin (idempotent).
    void start();
    /// From now on a failure sets `stop`; at once when the check has failed already.
    void stop_on_failure(std::atomic<bool>& stop);
    /// Starts the check if need be and waits for its end.
    void wait();
    /// wait(), then throws the check's error.
    void finish();

  private:
    void run();

    const std::vector<RenderImage> images_;
    std::mutex mutex_;
    std::condition_variable start_;
    bool started_ = false, dropped_ = false;
    std::exception_ptr failure_;
    std::atomic<bool>* stop_ = nullptr;
    std::thread thread_; ///< last: it starts once the members it uses are there
};

} // namespace candela::app
