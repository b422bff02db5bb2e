#pragma once
// The image of `candela render` while it runs: `--write-every` writes the film's current image
// to the output files (the image, and the preview and sample-rate image where asked), and
// `--display-server` streams it to the tev viewer. Both work from copies taken at pass
// boundaries, on a thread of their own, so the render never waits for a disk or a network; a
// failure of either is a warning and never costs the render.
#include "report.h"

#include "candela/io/tev_client.h"
#include "candela/util/stopwatch.h"

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace candela::app {

class LiveView {
  public:
    /// Idle (no thread) unless `job.args` asks for either option, and on every rank but the root.
    explicit LiveView(const ImageJob& job);
    ~LiveView();
    LiveView(const LiveView&) = delete;
    LiveView& operator=(const LiveView&) = delete;

    /// At a pass boundary: hands the thread a copy of what is due (the film for the files every
    /// --write-every seconds, its colours for the viewer every kFrameSeconds); a copy not yet
    /// taken up is replaced by the newer one. Nothing for the last pass: the final images follow.
    void on_pass(const RenderState& st);

    /// After the last pass, before the final images: the viewer gets `film` (when there is one),
    /// a file write not yet begun is dropped, and the thread ends.
    void finish(const Film* film);

    /// The second Ctrl-C: no more writes or sends; a file write under way ends first, a send
    /// is cut short. The thread is left to the process's end.
    void halt();

    /// Seconds between two frames sent to the viewer, at most: a viewer shows the render's
    /// progress at a glance, and each frame costs a pass boundary the film's colours.
    static constexpr double kFrameSeconds = 0.5;

  private:
    void run();
    void connect();
    void stream(const std::vector<float>& rgb);
    void write(const Film& film, double seconds);
    void warn(const std::string& what);

    const ImageJob& job_;
    std::optional<TevAddress> viewer_;
    std::atomic<bool> streaming_{false}; ///< a viewer is wanted and has not failed
    Stopwatch render_time_, since_write_, since_frame_;
    bool framed_ = false; ///< a frame went to the thread (the first is due at the first pass)

    std::mutex mutex_;
    std::condition_variable wake_, idle_;
    std::optional<Film> film_; ///< for the files, with the render's seconds then
    double film_seconds_ = 0.0;
    std::vector<float> frame_; ///< for the viewer; empty when none waits
    bool writing_ = false, ending_ = false, halted_ = false;
    std::unique_ptr<TevClient> client_; ///< set by the thread; abort() from halt()
    bool created_ = false;              ///< the viewer's image exists
    std::string last_failure_;          ///< of the file writes, warned about once
    std::thread thread_;
};

} // namespace candela::app
