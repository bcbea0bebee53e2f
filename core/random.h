#pragma once
// Seeded random draws that are the same bits with any standard library: std::mt19937_64 (fully specified by the
// standard) turned into uniform doubles (53 bits) and normal ones (Box-Muller) by our own arithmetic, not by
// std::*_distribution, whose algorithms each library chooses. Only std::sin/cos/log/sqrt could differ in the last
// bit on another libm.

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace fvm {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Normal() {                                                                  // Box-Muller, one value per pair
    const double u1 = 1.0 - Uniform();                                                // (0, 1]: log is finite
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// SplitMix64's output function [Steele 2014]: the generator's next number from state z (the state advanced by the
// golden gamma, then mixed). Every seed fvm derives from another goes through it.
inline std::uint64_t SplitMix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// A seed for stream `index` of `seed` (SplitMix64 of both): Monte Carlo run i draws from Random(StreamSeed(seed, i)),
// so a run's draws depend on neither the thread that made it nor the other runs.
inline std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t index) { return SplitMix64(SplitMix64(seed) ^ index); }

// The n-th number (from 0) of the SplitMix64 sequence started at `seed`: the seeds of a simulation's named parts
// (fvm simulate tracker: 0 the machine, 1 the point cloud, 2 the noise, 3 the validation points), which never share
// draws.
inline std::uint64_t SequenceSeed(std::uint64_t seed, std::uint64_t n) { return SplitMix64(seed + 0x9e3779b97f4a7c15ULL * n); }

}  // namespace fvm
