// The image of a render while it runs: --write-every and --display-server (live.h).
#include "live.h"

#include "candela/render/adaptive.h"
#include "candela/render/output.h"
#include "candela/util/error.h"
#include "candela/util/log.h"

#include <cstdio>
#include <fmt/format.h>
#include <utility>

namespace candela::app {

namespace {

/// A viewer that does not answer within this is taken to be absent: a local or LAN viewer
/// answers in milliseconds.
constexpr double kConnectSeconds = 2.0;
/// A send that cannot go on for this long means the viewer stopped reading; streaming stops.
constexpr double kSendSeconds = 2.0;

/// The channels sent to the viewer, interleaved in film_rgb()'s order.
const std::vector<std::string>& viewer_channels() {
    static const std::vector<std::string> names = {"R", "G", "B"};
    return names;
}

} // namespace

LiveView::LiveView(const ImageJob& job) : job_(job) {
    const RenderArgs& a = job.args;
    if (!job.ctx.root() || (a.write_every <= 0.0 && a.display_server.empty())) return;
    if (!a.display_server.empty()) {
        viewer_ = parse_tev_address(a.display_server); // checked when parsed
        streaming_ = viewer_.has_value();
    }
    thread_ = std::thread([this] { run(); });
}

LiveView::~LiveView() {
    halt();
    if (thread_.joinable()) thread_.join();
}

void LiveView::on_pass(const RenderState& st) {
    if (!thread_.joinable() || make_pass_policy(job_.args.settings)->finished(st)) return;
    const double every = job_.args.write_every;
    const bool write_due = every > 0.0 && since_write_.seconds() >= every;
    const bool frame_due = streaming_ && (!framed_ || since_frame_.seconds() >= kFrameSeconds);
    if (!write_due && !frame_due) return;
    // The copies are made here, outside the lock: the thread may be busy with the last ones.
    std::optional<Film> film;
    if (write_due) film = st.film;
    std::vector<float> rgb;
    if (frame_due) rgb = film_rgb(st.film);
    std::lock_guard<std::mutex> lock(mutex_);
    if (ending_ || halted_) return;
    if (write_due) {
        film_ = std::move(film);
        film_seconds_ = render_time_.seconds();
        since_write_.restart();
    }
    if (frame_due) {
        frame_ = std::move(rgb);
        since_frame_.restart();
        framed_ = true;
    }
    wake_.notify_one();
}

void LiveView::finish(const Film* film) {
    if (!thread_.joinable()) return;
    {
        std::lock_guard<std::mutex> lock(mutex_);
        film_.reset();
        if (film && streaming_) frame_ = film_rgb(*film);
        ending_ = true;
        wake_.notify_one();
    }
    thread_.join();
    std::lock_guard<std::mutex> lock(mutex_);
    client_.reset(); // closed with everything sent: the viewer keeps the image
}

void LiveView::halt() {
    std::unique_lock<std::mutex> lock(mutex_);
    halted_ = true;
    film_.reset();
    frame_.clear();
    if (client_) client_->abort();
    wake_.notify_one();
    idle_.wait(lock, [this] { return !writing_; });
}

void LiveView::run() {
    if (viewer_) connect();
    std::unique_lock<std::mutex> lock(mutex_);
    while (true) {
        wake_.wait(lock, [this] { return halted_ || ending_ || film_ || !frame_.empty(); });
        if (halted_) return;
        if (film_) {
            const Film film = std::move(*film_);
            film_.reset();
            writing_ = true;
            const double seconds = film_seconds_;
            lock.unlock();
            write(film, seconds);
            lock.lock();
            writing_ = false;
            idle_.notify_all();
        } else if (!frame_.empty()) {
            const std::vector<float> rgb = std::move(frame_);
            frame_.clear();
            lock.unlock();
            stream(rgb);
            lock.lock();
        } else if (ending_) {
            return;
        }
    }
}

void LiveView::connect() {
    try {
        auto client = std::make_unique<TevClient>(*viewer_, kConnectSeconds, kSendSeconds);
        std::lock_guard<std::mutex> lock(mutex_);
        if (!halted_) client_ = std::move(client);
    } catch (const Error& e) {
        streaming_ = false;
        warn(std::string(e.what()) + "; the render goes on without it");
    }
}

void LiveView::stream(const std::vector<float>& rgb) {
    if (!client_ || !streaming_) return;
    const RenderSettings& s = job_.args.settings;
    const int w = s.region.full() ? s.width : s.region.w;
    const int h = s.region.full() ? s.height : s.region.h;
    const std::string& name = job_.args.output;
    try {
        if (!created_) client_->create_image(name, s.width, s.height, viewer_channels(), true);
        created_ = true;
        client_->update_image(name, viewer_channels(), s.region.x, s.region.y, w, h, rgb);
    } catch (const Error& e) {
        streaming_ = false;
        std::lock_guard<std::mutex> lock(mutex_);
        if (!halted_) warn(std::string(e.what()) + "; streaming stopped, the render goes on");
    }
}

void LiveView::write(const Film& film, double seconds) {
    try {
        write_job_images(job_, film, seconds, true);
    } catch (const Error& e) {
        // Once per distinct failure, as the periodic checkpoint's.
        if (e.what() == last_failure_) return;
        last_failure_ = e.what();
        if (log_level() >= LogLevel::Warning) fmt::print(stderr, "{}\n", warning_line(e));
    }
}

void LiveView::warn(const std::string& what) {
    print_warning(what);
}

} // namespace candela::app
