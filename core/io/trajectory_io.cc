#include "core/io/trajectory_io.h"

#include <cmath>
#include <iomanip>

#include "core/error.h"
#include "core/io/atomic_file.h"
#include "core/io/text_lines.h"

namespace dala {
namespace {

constexpr double kQuaternionNormTolerance = 1e-2;  // Files keep ~6 decimals; be lenient.
constexpr double kRotationTolerance = 1e-2;        // |R^T R - I| for KITTI rows.

Eigen::Quaterniond CheckedQuaternion(const std::string& path, int line, double qx, double qy,
                                     double qz, double qw) {
  Eigen::Quaterniond q(qw, qx, qy, qz);
  const double n = q.norm();
  if (std::abs(n - 1.0) > kQuaternionNormTolerance) {
    throw Error() << path << ":" << line << ": quaternion norm is " << n
                         << ", expected 1 (is the column order right? TUM is "
                            "'t tx ty tz qx qy qz qw', EuRoC is 't px py pz qw qx qy qz')";
  }
  return q.normalized();
}

void CheckIncreasing(const std::string& path, int line, const Trajectory& traj, int64_t t_ns) {
  // Equal stamps are kept (real files have them, e.g. EuRoC V1_02); going back in time is an error.
  if (!traj.empty() && t_ns < traj.poses.back().t_ns) {
    throw Error() << path << ":" << line << ": timestamp " << SecondsFromNs(t_ns)
                         << " s goes back in time (previous " << SecondsFromNs(traj.poses.back().t_ns)
                         << " s); sort the file by time";
  }
}

}  // namespace

TrajectoryFormat ParseTrajectoryFormat(const std::string& name) {
  if (name == "auto") return TrajectoryFormat::kAuto;
  if (name == "tum") return TrajectoryFormat::kTum;
  if (name == "kitti") return TrajectoryFormat::kKitti;
  if (name == "euroc") return TrajectoryFormat::kEurocCsv;
  throw Error() << "unknown trajectory format '" << name
                       << "': use one of auto, tum, kitti, euroc";
}

TrajectoryFormat DetectTrajectoryFormat(const std::string& path) {
  const auto lines = ReadDataLines(path, "a trajectory file");
  if (lines.empty()) {
    throw Error() << "'" << path << "' holds no trajectory (no data lines)";
  }
  const NumberedLine& first = lines.front();
  const size_t n = ParseNumbers(path, first).size();
  const bool has_comma = first.text.find(',') != std::string::npos;
  if (has_comma && n >= 8) return TrajectoryFormat::kEurocCsv;
  if (n == 12) return TrajectoryFormat::kKitti;
  if (n == 8) return TrajectoryFormat::kTum;
  throw Error() << path << ":" << first.number << ": cannot tell the format from " << n
                       << " columns: TUM has 8 ('t tx ty tz qx qy qz qw'), KITTI 12 (a 3x4 "
                          "matrix), EuRoC csv 8 or more comma-separated";
}

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format) {
  if (format == TrajectoryFormat::kAuto) format = DetectTrajectoryFormat(path);
  const auto lines = ReadDataLines(path, "a trajectory file");
  if (lines.empty()) throw Error() << "'" << path << "' holds no trajectory (no data lines)";
  Trajectory traj;
  traj.has_timestamps = format != TrajectoryFormat::kKitti;
  traj.poses.reserve(lines.size());
  for (const NumberedLine& line : lines) {
    const std::vector<double> v = ParseNumbers(path, line);
    switch (format) {
      case TrajectoryFormat::kTum: {
        if (v.size() != 8) {
          throw Error() << path << ":" << line.number << ": expected 8 columns (TUM: t tx "
                               << "ty tz qx qy qz qw), got " << v.size();
        }
        const int64_t t_ns = ParseSecondsAsNs(path, line.number, SplitFields(line.text)[0]);
        CheckIncreasing(path, line.number, traj, t_ns);
        traj.Add(t_ns, MakePose(CheckedQuaternion(path, line.number, v[4], v[5], v[6], v[7]),
                                Eigen::Vector3d(v[1], v[2], v[3])));
        break;
      }
      case TrajectoryFormat::kEurocCsv: {
        if (v.size() < 8) {
          throw Error() << path << ":" << line.number << ": expected at least 8 columns "
                               << "(EuRoC: t_ns, px, py, pz, qw, qx, qy, qz), got " << v.size();
        }
        // Integer nanoseconds: parsed exactly (a double keeps only ~16 digits of 19).
        const int64_t t_ns = ParseInt64(path, line.number, SplitFields(line.text)[0]);
        CheckIncreasing(path, line.number, traj, t_ns);
        traj.Add(t_ns, MakePose(CheckedQuaternion(path, line.number, v[5], v[6], v[7], v[4]),
                                Eigen::Vector3d(v[1], v[2], v[3])));
        break;
      }
      case TrajectoryFormat::kKitti: {
        if (v.size() != 12) {
          throw Error() << path << ":" << line.number
                               << ": expected 12 columns (KITTI: row-major 3x4 [R|t]), got "
                               << v.size();
        }
        Eigen::Matrix3d R;
        R << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
        const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
        if (err > kRotationTolerance || R.determinant() < 0.0) {
          throw Error() << path << ":" << line.number
                               << ": the 3x3 block is not a rotation (|R^T R - I| = " << err
                               << "); is this a KITTI pose file?";
        }
        // The nearest rotation, not a quaternion round trip: KITTI files keep ~7 digits, and a
        // quaternion moves the angle by the rounding of the diagonal (~1e-7 rad), which shifts
        // small RPE rotation errors by ~1e-5 relative (tests/core/eval/reference_test.cc).
        const int64_t index = static_cast<int64_t>(traj.size());
        traj.Add(index * 1000000000LL,
                 MakePose(NearestRotation(R), Eigen::Vector3d(v[3], v[7], v[11])));
        break;
      }
      case TrajectoryFormat::kAuto: break;
    }
  }
  return traj;
}

std::vector<int64_t> ReadTimesFile(const std::string& times_path) {
  std::vector<int64_t> times;
  for (const NumberedLine& line : ReadDataLines(times_path, "a times file")) {
    const auto v = ParseNumbers(times_path, line);
    if (v.size() != 1) {
      throw Error() << times_path << ":" << line.number
                           << ": expected one time in seconds per line, got " << v.size()
                           << " columns";
    }
    const int64_t t_ns = ParseSecondsAsNs(times_path, line.number, SplitFields(line.text)[0]);
    if (!times.empty() && t_ns <= times.back()) {
      throw Error() << times_path << ":" << line.number
                           << ": time does not increase; sort the file";
    }
    times.push_back(t_ns);
  }
  return times;
}

void ApplyTimes(const std::string& times_path, Trajectory* trajectory) {
  const std::vector<int64_t> times = ReadTimesFile(times_path);
  if (times.size() != trajectory->size()) {
    throw Error() << "'" << times_path << "' has " << times.size()
                         << " times but the trajectory has " << trajectory->size()
                         << " poses; they must match row for row";
  }
  for (size_t i = 0; i < times.size(); ++i) trajectory->poses[i].t_ns = times[i];
  trajectory->has_timestamps = true;
}

void WriteTrajectoryTum(const std::string& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, [&](std::ostream& os) {
    os << "# timestamp tx ty tz qx qy qz qw\n";
    for (const StampedPose& p : trajectory.poses) {
      const Eigen::Quaterniond q(p.T_w_c.linear());
      const Eigen::Vector3d t = p.T_w_c.translation();
      // Sign, whole seconds and nanoseconds apart: t_ns / 1e9 truncates towards zero, so a time
      // in (-1 s, 0) has 0 whole seconds and its sign would be lost.
      os << (p.t_ns < 0 ? "-" : "") << std::abs(p.t_ns / 1000000000LL) << "." << std::setw(9)
         << std::setfill('0') << std::abs(p.t_ns % 1000000000LL) << std::setfill(' ')
         << std::setprecision(9)
         << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " " << q.y() << " "
         << q.z() << " " << q.w() << "\n";
    }
  });
}

void WriteTrajectoryKitti(const std::string& path, const Trajectory& trajectory) {
  WriteFileAtomically(path, [&](std::ostream& os) {
    os << std::scientific << std::setprecision(9);
    for (const StampedPose& p : trajectory.poses) {
      const Eigen::Matrix<double, 3, 4> M = p.T_w_c.matrix().topRows<3>();
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 4; ++c) os << M(r, c) << ((r == 2 && c == 3) ? "\n" : " ");
      }
    }
  });
}

}  // namespace dala
