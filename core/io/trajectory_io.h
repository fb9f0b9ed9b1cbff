#ifndef DALA_CORE_IO_TRAJECTORY_IO_H_
#define DALA_CORE_IO_TRAJECTORY_IO_H_

#include <string>

#include "core/trajectory.h"

namespace dala {

// The trajectory file formats the field uses.
//  - kTum:   "t tx ty tz qx qy qz qw" per line, t in seconds, '#' comments.
//  - kKitti: 12 numbers per line, the row-major 3x4 [R|t] of T_w_c; no timestamps.
//  - kEurocCsv: "t_ns, px, py, pz, qw, qx, qy, qz[, ...]" (EuRoC ground truth), '#' header.
enum class TrajectoryFormat { kAuto, kTum, kKitti, kEurocCsv };

// Parses "auto", "tum", "kitti", "euroc"; throws dala::Error naming the accepted values.
TrajectoryFormat ParseTrajectoryFormat(const std::string& name);

// Detects the format from the first data line of the file (column count and separators).
TrajectoryFormat DetectTrajectoryFormat(const std::string& path);

// Reads a trajectory. Throws dala::Error naming the file and line on: a missing file, a line with
// the wrong number of columns or a non-number, a non-unit or zero quaternion, a rotation that is
// not orthonormal, timestamps that do not increase, an empty file. For KITTI, row i gets
// t_ns = i * 1e9 and has_timestamps = false (see ApplyTimes), and its 3x3 block is replaced by the
// nearest rotation (NearestRotation); TUM and EuRoC quaternions are normalized.
Trajectory ReadTrajectory(const std::string& path,
                          TrajectoryFormat format = TrajectoryFormat::kAuto);

// Reads a KITTI "times.txt" (one time in seconds per line) and applies it to a trajectory read
// from a KITTI file; the row counts must match (dala::Error otherwise).
void ApplyTimes(const std::string& times_path, Trajectory* trajectory);
std::vector<int64_t> ReadTimesFile(const std::string& times_path);

// Writers; atomic (a temporary file renamed into place). TUM writes seconds with 9 decimals.
void WriteTrajectoryTum(const std::string& path, const Trajectory& trajectory);
void WriteTrajectoryKitti(const std::string& path, const Trajectory& trajectory);

}  // namespace dala

#endif  // DALA_CORE_IO_TRAJECTORY_IO_H_
