#pragma once
// `candela merge`: adds renders of one frame made with disjoint sample ranges
// (`--sample-offset`), for users who split a frame over a job scheduler instead of MPI.
//
// A candela EXR stores per-pixel means and a `samples` channel (the count of finite samples),
// so each input's sums are recovered as mean x samples. The merged mean therefore equals the
// mean of one render over the union of the ranges up to float rounding: each input mean
// carries a relative error of at most 2^-24 (it was rounded to float once), so the merged
// mean differs from the exactly summed one by at most about 2^-23 times the
// samples-weighted mean of the inputs' magnitudes (docs/distributed.md).
#include "candela/io/image_io.h"

#include <cstdint>
#include <string>
#include <vector>

namespace candela {

/// The sample indices one input covers, from its metadata: [offset, offset + spp) asked for,
/// and [offset, used_last) really used by its pixels (the relative sampler's -s is a budget, so
/// a pixel may go past offset + spp; an interrupted render stops short of it).
struct SampleRange {
    std::uint64_t first = 0, last = 0;
    std::uint64_t used_last = 0;
};

/// The range of a candela EXR (its `candela:sample_offset`, `candela:spp` and
/// `candela:sample_end`; files without the last count as having used [offset, offset + spp)).
/// Throws Error(Usage) naming `name` when the metadata is missing or malformed.
SampleRange sample_range_of(const ImageData& img, const std::string& name);

/// Merges candela EXR images of the same frame rendered with disjoint sample ranges: radiance
/// and the auxiliary channels become samples-weighted means, `variance.*` is recomputed from
/// the recovered sums and sums of squares, `samples` is added, A is 1 where any sample landed.
/// The metadata is the first input's, with spp, sample_offset, the sample and drop counts, the
/// render time and the interrupted flag combined, plus `candela:merged_ranges` and the
/// commands that made the parts (`candela:part_commands`); the first input's command line and
/// session commands are not kept (merge_exr_files records the merge's own).
/// Throws Error(Usage) naming the inputs (`names`, parallel to `images`) when they differ in
/// size, channels or image-defining settings (scene, seed, integrator, sampler, depth, light
/// samples), when fewer than two are given, or when the sample indices they really used overlap
/// on shared pixels (repeated indices are the same samples again, which would bias the variance
/// and the sample counts and waste the render).
ImageData merge_images(const std::vector<ImageData>& images, const std::vector<std::string>& names);

/// Reads every input EXR, merges them (merge_images) and writes `output` atomically, with
/// `command_line` (the merge's own, when not empty) as its `candela:command_line`.
/// Throws Error(Io) for unreadable or unwritable files, Error(Usage) as merge_images.
ImageData merge_exr_files(const std::vector<std::string>& inputs, const std::string& output,
                          const std::string& command_line = "");

} // namespace candela
