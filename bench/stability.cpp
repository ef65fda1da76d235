#include "benchmarks.hpp"
namespace tumble_bench { void run_stability(const Options&) {} }
