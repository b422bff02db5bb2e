// The render command's check that its images can be written (image_format_check.h).
#include "image_format_check.h"

#include "candela/io/image_io.h"

#include <utility>

namespace candela::app {

ImageFormatCheck::ImageFormatCheck(std::vector<RenderImage> images)
    : images_(std::move(images)), thread_([this] { run(); }) {}

ImageFormatCheck::~ImageFormatCheck() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        dropped_ = !started_;
        started_ = true;
    }
    start_.notify_one();
    if (thread_.joinable()) thread_.join();
}

void ImageFormatCheck::start() {
    std::lock_guard<std::mutex> lock(mutex_);
    started_ = true;
    start_.notify_one();
}

void ImageFormatCheck::stop_on_failure(std::atomic<bool>& stop) {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = &stop;
    if (failure_) stop = true;
}

void ImageFormatCheck::wait() {
    start();
    if (thread_.joinable()) thread_.join();
}

void ImageFormatCheck::finish() {
    wait();
    if (failure_) std::rethrow_exception(failure_);
}

void ImageFormatCheck::run() {
    {
        std::unique_lock<std::mutex> lock(mutex_);
        start_.wait(lock, [this] { return started_; });
        if (dropped_) return;
    }
    try {
        for (const RenderImage& image : images_)
            check_image_format(image.path, image.kind);
    } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        failure_ = std::current_exception();
        if (stop_) *stop_ = true;
    }
}

} // namespace candela::app
