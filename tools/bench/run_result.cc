#include "tools/bench/run_result.h"

#include "core/error.h"

namespace dala::bench {
namespace {

template <typename T>
void Put(nlohmann::json* j, const char* key, const std::optional<T>& v) {
  (*j)[key] = v ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

template <typename T>
void Get(const nlohmann::json& j, const char* key, std::optional<T>* v) {
  if (j.contains(key) && !j.at(key).is_null()) *v = j.at(key).get<T>();
}

// Applies `f(key, member)` to every field, so that writing and reading list them once.
template <typename R, typename F>
void ForEachField(R& r, F&& f) {
  f("index", r.index);
  f("sequence", r.sequence);
  f("config", r.config);
  f("variant", r.variant);
  f("start", r.start);
  f("seed", r.seed);
  f("estimator", r.estimator);
  f("mode", r.mode);
  f("status", r.status);
  f("error", r.error);
  f("ate_rmse", r.ate_rmse);
  f("rpe_trans", r.rpe_trans);
  f("t_err_percent", r.t_err_percent);
  f("ms_median", r.ms_median);
  f("ms_p95", r.ms_p95);
  f("ms_max", r.ms_max);
  f("fps", r.fps);
  f("peak_rss_mb", r.peak_rss_mb);
  f("wall_s", r.wall_s);
  f("landmarks", r.landmarks);
  f("keyframes", r.keyframes);
  f("keyframes_in_map", r.keyframes_in_map);
  f("disparity_offset_px", r.disparity_offset_px);
  f("tracking_failures", r.tracking_failures);
  f("frames", r.frames);
  f("alignment", r.alignment);
  f("pairs", r.pairs);
  f("path_length_m", r.path_length_m);
  f("ate_mean", r.ate_mean);
  f("ate_median", r.ate_median);
  f("ate_max", r.ate_max);
  f("scale", r.scale);
  f("rpe_rot_deg", r.rpe_rot_deg);
  f("rpe10_trans", r.rpe10_trans);
  f("rpe10_rot_deg", r.rpe10_rot_deg);
  f("r_err_deg_per_100m", r.r_err_deg_per_100m);
  f("exit_code", r.exit_code);
  f("signal", r.signal);
  f("run_dir", r.run_dir);
  f("plot_trajectory", r.plot_trajectory);
  f("plot_timing", r.plot_timing);
  f("command", r.command);
}

struct Writer {
  nlohmann::json* j;
  template <typename T>
  void operator()(const char* key, const std::optional<T>& v) const {
    Put(j, key, v);
  }
  template <typename T>
  void operator()(const char* key, const T& v) const {
    (*j)[key] = v;
  }
};

struct Reader {
  const nlohmann::json& j;
  template <typename T>
  void operator()(const char* key, std::optional<T>& v) const {
    Get(j, key, &v);
  }
  template <typename T>
  void operator()(const char* key, T& v) const {
    if (j.contains(key)) v = j.at(key).get<T>();
  }
};

}  // namespace

std::string RunKey(const BenchRunResult& r) {
  return (r.variant.empty() ? r.sequence : r.sequence + "@" + r.variant) + "/" + r.config;
}

nlohmann::json ToJson(const BenchRunResult& r) {
  nlohmann::json j = nlohmann::json::object();
  ForEachField(r, Writer{&j});
  return j;
}

BenchRunResult BenchRunResultFromJson(const nlohmann::json& j, const std::string& where) {
  BenchRunResult r;
  try {
    if (!j.is_object()) throw Error() << "expected an object";
    for (const char* key : {"sequence", "config", "status"}) {
      if (!j.contains(key)) throw Error() << "missing key '" << key << "'";
    }
    ForEachField(r, Reader{j});
  } catch (const nlohmann::json::exception& e) {
    throw Error() << where << ": not a dala bench run result: " << e.what();
  } catch (const Error& e) {
    throw Error() << where << ": not a dala bench run result: " << e.what();
  }
  return r;
}

}  // namespace dala::bench
