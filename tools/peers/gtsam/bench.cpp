// GTSAM 4.3's C++ preintegration timed on preint's benchmark stream (tools/peers/gtsam/run.sh
// builds and runs it; docs/PERFORMANCE.md, "Against GTSAM 4.3, in the same run").
//
// The harness links the PyPI gtsam 4.3.0 wheel's libgtsam and calls the library's own compiled
// `integrateMeasurement` of
//   PreintegratedImuMeasurementsT<ManifoldPreintegration>   (Forster's on-manifold update)
//   PreintegratedImuMeasurementsT<TangentPreintegration>    (PreintegratedImuMeasurements, the default)
//   PreintegratedImuMeasurementsT<LieGroupPreintegration>   (SE_2(3) group exponential)
//   PreintegratedImuMeasurementsT<GalileanPreintegration>   (PreintegratedImuMeasurementsG, Gal(3))
//   PreintegratedCombinedMeasurementsT<TangentPreintegration> (PreintegratedCombinedMeasurements, 15x15)
// each of which propagates the 9x9 (15x15) covariance and the bias Jacobians per sample.
//
// It declares only the entry points it calls, with the signatures the library exports
// (`nm -D --defined-only libgtsam*.so | c++filt`), and no GTSAM header: the objects live in
// buffers larger than the library's classes and are built by the library's own constructors,
// and the parameters are filled at the offsets the library reads (the disassembly of
// PreintegrationParams::equals / PreintegrationCombinedParams::equals). `--params` prints them
// through the library's own `print`, and `--deltas` prints each backend's ΔR, Δv, Δp and
// preintMeasCov() after the stream, which run.sh compares with preint's and with the wheel's Python
// bindings (bit for bit).
//
// Usage:
//   bench [--samples N] [--runs K]   one round: per backend, the median of K runs of N samples,
//                                    ns per integrateMeasurement call, one "name value" per line
//   bench --deltas [--samples N]     ΔR, Δv, Δp and covariance after N samples (%.17g, column-major)
//   bench --csv FILE [--samples N]   write the stream as an EuRoC imu0/data.csv
//   bench --params                   print the parameters through libgtsam's print
//   bench --only NAME [--samples N]  integrate the stream once with one backend (manifold,
//                                    tangent, liegroup, galilean, combined), for valgrind:
//                                    run.sh's INSTR=1 counts the instructions in integrate<…>

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <vector>

// ---------------------------------------------------------------------------------------------
// The library's entry points (names and argument types as exported by libgtsam 4.3.0).
namespace gtsam {

using Vector3 = Eigen::Matrix<double, 3, 1>;
using Matrix3 = Eigen::Matrix<double, 3, 3>;
using Matrix15 = Eigen::Matrix<double, 15, 15>;

namespace imuBias {
/// Two Vector3 (accelerometer, gyroscope) in the library; zero here, with room to spare.
class ConstantBias {
 public:
  alignas(16) unsigned char raw[256];
};
}  // namespace imuBias

/// Byte images of the parameter classes (filled by make_params below).
class PreintegrationParams {
 public:
  alignas(64) unsigned char raw[1024];
};
class PreintegrationCombinedParams {
 public:
  alignas(64) unsigned char raw[2048];
};

class Rot3 {
 public:
  alignas(64) unsigned char raw[256];
  Matrix3 matrix() const;
};

// Backends: the accessors each one exports.
class TangentPreintegration {
 public:
  Rot3 deltaRij() const;
  Vector3 deltaPij() const;
  Vector3 deltaVij() const;
};
class ManifoldPreintegration {
 public:
  Rot3 deltaRij() const;
  Vector3 deltaPij() const;
  Vector3 deltaVij() const;
};
class GalileanPreintegration {
 public:
  Rot3 deltaRij() const;
  Vector3 deltaPij() const;
  Vector3 deltaVij() const;
};
class LieGroupPreintegration;  // derives from ManifoldPreintegration

template <class Backend>
class PreintegratedImuMeasurementsT {
 public:
  PreintegratedImuMeasurementsT(const std::shared_ptr<PreintegrationParams>& p,
                                const imuBias::ConstantBias& biasHat);
  ~PreintegratedImuMeasurementsT();
  void integrateMeasurement(const Vector3& measuredAcc, const Vector3& measuredOmega,
                            double dt);
  Eigen::MatrixXd preintMeasCov() const;
  alignas(64) unsigned char raw[8192];
};

template <class Backend>
class PreintegratedCombinedMeasurementsT {
 public:
  PreintegratedCombinedMeasurementsT(const std::shared_ptr<PreintegrationCombinedParams>& p,
                                     const imuBias::ConstantBias& biasHat,
                                     const Matrix15& preintMeasCov);
  ~PreintegratedCombinedMeasurementsT();
  void integrateMeasurement(const Vector3& measuredAcc, const Vector3& measuredOmega,
                            double dt);
  Eigen::MatrixXd preintMeasCov() const;
  alignas(64) unsigned char raw[16384];
};

}  // namespace gtsam

// The parameter classes' vtables and print (built with the pre-C++11 std::string ABI, as the
// wheel is: compile with -D_GLIBCXX_USE_CXX11_ABI=0).
extern "C" void* _ZTVN5gtsam20PreintegrationParamsE[];
extern "C" void* _ZTVN5gtsam28PreintegrationCombinedParamsE[];
extern "C" void _ZNK5gtsam20PreintegrationParams5printERKSs(const void* self, const std::string& s);
extern "C" void _ZNK5gtsam28PreintegrationCombinedParams5printERKSs(const void* self,
                                                                    const std::string& s);

// ---------------------------------------------------------------------------------------------
// Parameters: EuRoC densities as preint's PreintParams::from_noise(&ImuNoise::euroc()), gravity
// (0, 0, -9.81), no integration covariance, zero bias, no Coriolis, no sensor pose.
namespace params {
constexpr double kGyroNoise = 1.6968e-4, kGyroWalk = 1.9393e-5;
constexpr double kAccNoise = 2.0e-3, kAccWalk = 3.0e-3;

// Offsets in libgtsam 4.3.0 (x86-64): PreintegratedRotationParams {vptr; Matrix3
// gyroscopeCovariance @8; optional<Vector3> omegaCoriolis @80 (engaged @104); optional<Pose3>
// body_P_sensor @112 (engaged @216)}; PreintegrationParams {Matrix3 accelerometerCovariance
// @224; Matrix3 integrationCovariance @296; bool use2ndOrderCoriolis @368; Vector3 n_gravity
// @376; ImuFactorErrorMode @400 (2 = Logmap, the default)}; PreintegrationCombinedParams
// {Matrix3 biasAccCovariance @408; Matrix3 biasOmegaCovariance @480; Matrix6 biasAccOmegaInt
// @560}.
constexpr size_t kGyroCov = 8, kOmegaCoriolisEngaged = 104, kBodyPSensorEngaged = 216;
constexpr size_t kAccCov = 224, kIntegrationCov = 296, kSecondOrderCoriolis = 368;
constexpr size_t kGravity = 376, kErrorMode = 400;
constexpr size_t kBiasAccCov = 408, kBiasOmegaCov = 480;

void put_matrix3(unsigned char* raw, size_t at, double diagonal) {
  const gtsam::Matrix3 m = gtsam::Matrix3::Identity() * diagonal;
  std::memcpy(raw + at, m.data(), sizeof(double) * 9);
}

void fill(unsigned char* raw, void** vtable) {
  void* vptr = vtable + 2;  // past offset-to-top and typeinfo
  std::memcpy(raw, &vptr, sizeof vptr);
  put_matrix3(raw, kGyroCov, kGyroNoise * kGyroNoise);
  raw[kOmegaCoriolisEngaged] = 0;
  raw[kBodyPSensorEngaged] = 0;
  put_matrix3(raw, kAccCov, kAccNoise * kAccNoise);
  put_matrix3(raw, kIntegrationCov, 0.0);
  raw[kSecondOrderCoriolis] = 0;
  const double g[3] = {0.0, 0.0, -9.81};
  std::memcpy(raw + kGravity, g, sizeof g);
  const int mode = 2;
  std::memcpy(raw + kErrorMode, &mode, sizeof mode);
}

std::shared_ptr<gtsam::PreintegrationParams> imu() {
  auto p = std::make_shared<gtsam::PreintegrationParams>();
  std::memset(p->raw, 0, sizeof p->raw);
  fill(p->raw, _ZTVN5gtsam20PreintegrationParamsE);
  return p;
}

std::shared_ptr<gtsam::PreintegrationCombinedParams> combined() {
  auto p = std::make_shared<gtsam::PreintegrationCombinedParams>();
  std::memset(p->raw, 0, sizeof p->raw);
  fill(p->raw, _ZTVN5gtsam28PreintegrationCombinedParamsE);
  put_matrix3(p->raw, kBiasAccCov, kAccWalk * kAccWalk);
  put_matrix3(p->raw, kBiasOmegaCov, kGyroWalk * kGyroWalk);
  return p;  // biasAccOmegaInt stays zero
}
}  // namespace params

// ---------------------------------------------------------------------------------------------
// preint_sim::synthetic_stream: 200 Hz, t_k = k·5 ms, sinusoidal rates and specific force.
struct Stream {
  std::vector<long long> t_ns;
  std::vector<gtsam::Vector3> gyro, acc;
  std::vector<double> dt;  // (t_{k+1} − t_k)·1e-9, the interval integrateMeasurement holds sample k over
};

Stream synthetic_stream(size_t n) {
  Stream s;
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * 0.005;
    s.t_ns.push_back(static_cast<long long>(k) * 5000000LL);
    s.gyro.emplace_back(0.3 * std::sin(1.1 * t), 0.2 * std::cos(0.7 * t),
                        0.5 * std::sin(0.3 * t) + 0.1);
    s.acc.emplace_back(0.5 * std::sin(0.9 * t), 0.3 * std::cos(1.3 * t),
                       9.81 + 0.2 * std::sin(0.5 * t));
  }
  for (size_t k = 0; k + 1 < n; ++k)
    s.dt.push_back(static_cast<double>(s.t_ns[k + 1] - s.t_ns[k]) * 1e-9);
  return s;
}

// ---------------------------------------------------------------------------------------------
using gtsam::GalileanPreintegration;
using gtsam::LieGroupPreintegration;
using gtsam::ManifoldPreintegration;
using gtsam::TangentPreintegration;
template <class B>
using Pim = gtsam::PreintegratedImuMeasurementsT<B>;
using Combined = gtsam::PreintegratedCombinedMeasurementsT<TangentPreintegration>;

const gtsam::imuBias::ConstantBias& zero_bias() {
  static gtsam::imuBias::ConstantBias b{};
  return b;
}

template <class P>
__attribute__((noinline)) void integrate(P& pim, const Stream& s) {
  const size_t m = s.dt.size();
  for (size_t k = 0; k < m; ++k) pim.integrateMeasurement(s.acc[k], s.gyro[k], s.dt[k]);
}

/// ns per integrateMeasurement call of one run (a fresh object, built outside the timing).
template <class P, class Make>
double one_run(const Stream& s, Make make) {
  void* mem = std::aligned_alloc(64, sizeof(P));
  P* pim = make(mem);
  const auto t0 = std::chrono::steady_clock::now();
  integrate(*pim, s);
  const auto t1 = std::chrono::steady_clock::now();
  asm volatile("" : : "r"(pim) : "memory");
  pim->~P();
  std::free(mem);
  return std::chrono::duration<double, std::nano>(t1 - t0).count() / s.dt.size();
}

template <class P, class Make>
double median_run(const Stream& s, int runs, Make make) {
  std::vector<double> t;
  for (int r = 0; r < runs; ++r) t.push_back(one_run<P>(s, make));
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

template <class B>
Pim<B>* make_pim(void* mem, const std::shared_ptr<gtsam::PreintegrationParams>& p) {
  return new (mem) Pim<B>(p, zero_bias());
}

Combined* make_combined(void* mem, const std::shared_ptr<gtsam::PreintegrationCombinedParams>& p) {
  return new (mem) Combined(p, zero_bias(), gtsam::Matrix15::Zero());
}

void print_deltas(const char* name, const gtsam::Matrix3& R, const gtsam::Vector3& v,
                  const gtsam::Vector3& p, const Eigen::MatrixXd& cov) {
  std::printf("%s", name);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) std::printf(" %.17g", R(r, c));  // column-major
  for (int i = 0; i < 3; ++i) std::printf(" %.17g", v(i));
  for (int i = 0; i < 3; ++i) std::printf(" %.17g", p(i));
  for (Eigen::Index c = 0; c < cov.cols(); ++c)
    for (Eigen::Index r = 0; r < cov.rows(); ++r) std::printf(" %.17g", cov(r, c));
  std::printf("\n");
}

template <class B, class Access>
void deltas_of(const char* name, const Stream& s,
               const std::shared_ptr<gtsam::PreintegrationParams>& p) {
  void* mem = std::aligned_alloc(64, sizeof(Pim<B>));
  auto* pim = make_pim<B>(mem, p);
  integrate(*pim, s);
  const Access& a = *reinterpret_cast<const Access*>(pim);  // the backend is the base at offset 0
  print_deltas(name, a.deltaRij().matrix(), a.deltaVij(), a.deltaPij(), pim->preintMeasCov());
  pim->~Pim<B>();
  std::free(mem);
}

int main(int argc, char** argv) {
  size_t samples = 100000;
  int runs = 11;
  bool deltas = false, print_params = false;
  const char* csv = nullptr;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--samples" && i + 1 < argc) samples = std::strtoull(argv[++i], nullptr, 10);
    else if (a == "--runs" && i + 1 < argc) runs = std::atoi(argv[++i]);
    else if (a == "--deltas") deltas = true;
    else if (a == "--params") print_params = true;
    else if (a == "--csv" && i + 1 < argc) csv = argv[++i];
    else if (a == "--only" && i + 1 < argc) only = argv[++i];
    else {
      std::fprintf(stderr,
                   "usage: %s [--samples N] [--runs K] [--deltas] [--params] [--csv FILE] "
                   "[--only NAME]\n",
                   argv[0]);
      return 2;
    }
  }
  if (samples < 2 || runs < 1) {
    std::fprintf(stderr, "--samples must be at least 2 and --runs at least 1\n");
    return 2;
  }
  const auto p = params::imu();
  const auto pc = params::combined();
  if (print_params) {
    _ZNK5gtsam20PreintegrationParams5printERKSs(p.get(), std::string("PreintegrationParams"));
    _ZNK5gtsam28PreintegrationCombinedParams5printERKSs(pc.get(),
                                                        std::string("PreintegrationCombinedParams"));
    return 0;
  }
  const Stream s = synthetic_stream(samples);
  if (csv) {
    FILE* f = std::fopen(csv, "w");
    if (!f) return 1;
    std::fprintf(f, "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
                    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n");
    for (size_t k = 0; k < samples; ++k)
      std::fprintf(f, "%lld,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", s.t_ns[k], s.gyro[k](0),
                   s.gyro[k](1), s.gyro[k](2), s.acc[k](0), s.acc[k](1), s.acc[k](2));
    return std::fclose(f) == 0 ? 0 : 1;
  }
  if (!only.empty()) {
    auto once = [&](auto* pim) {
      integrate(*pim, s);
      using P = std::remove_pointer_t<decltype(pim)>;
      pim->~P();
    };
    void* mem = std::aligned_alloc(64, sizeof(Combined));
    if (only == "manifold") once(make_pim<ManifoldPreintegration>(mem, p));
    else if (only == "tangent") once(make_pim<TangentPreintegration>(mem, p));
    else if (only == "liegroup") once(make_pim<LieGroupPreintegration>(mem, p));
    else if (only == "galilean") once(make_pim<GalileanPreintegration>(mem, p));
    else if (only == "combined") once(make_combined(mem, pc));
    else {
      std::fprintf(stderr, "--only: manifold, tangent, liegroup, galilean or combined\n");
      return 2;
    }
    std::free(mem);
    return 0;
  }
  if (deltas) {
    // name R(9, column-major) v(3) p(3) cov(81 or 225, column-major)
    deltas_of<ManifoldPreintegration, ManifoldPreintegration>("manifold", s, p);
    deltas_of<TangentPreintegration, TangentPreintegration>("tangent", s, p);
    deltas_of<LieGroupPreintegration, ManifoldPreintegration>("liegroup", s, p);
    deltas_of<GalileanPreintegration, GalileanPreintegration>("galilean", s, p);
    void* mem = std::aligned_alloc(64, sizeof(Combined));
    Combined* c = make_combined(mem, pc);
    integrate(*c, s);
    const auto& a = *reinterpret_cast<const TangentPreintegration*>(c);
    print_deltas("combined", a.deltaRij().matrix(), a.deltaVij(), a.deltaPij(), c->preintMeasCov());
    c->~Combined();
    std::free(mem);
    return 0;
  }
  // One round: the backends one after the other, each the median of `runs` runs.
  std::printf("manifold %.2f\n",
              median_run<Pim<ManifoldPreintegration>>(s, runs, [&](void* m) { return make_pim<ManifoldPreintegration>(m, p); }));
  std::printf("tangent %.2f\n",
              median_run<Pim<TangentPreintegration>>(s, runs, [&](void* m) { return make_pim<TangentPreintegration>(m, p); }));
  std::printf("liegroup %.2f\n",
              median_run<Pim<LieGroupPreintegration>>(s, runs, [&](void* m) { return make_pim<LieGroupPreintegration>(m, p); }));
  std::printf("galilean %.2f\n",
              median_run<Pim<GalileanPreintegration>>(s, runs, [&](void* m) { return make_pim<GalileanPreintegration>(m, p); }));
  std::printf("combined %.2f\n",
              median_run<Combined>(s, runs, [&](void* m) { return make_combined(m, pc); }));
  return 0;
}
