#pragma once
// How much memory a solve may take: `--memory-limit SIZE` ("auto", a byte
// count, or a number with K, M, G or T, powers of 1024: "256M", "1.5G").
// "auto" is half of the machine's physical memory, leaving the rest to the
// system and to the other programs of a station.

#include <cstddef>
#include <string>

namespace lightstage::pipeline {

// Throws InputError naming --memory-limit and the text when it is neither.
std::size_t parse_memory_limit(const std::string& text);
std::size_t physical_memory_bytes();
// "1.5 GB", "256 MB", "12 kB" (powers of 1000, as people read them).
std::string describe_bytes(std::size_t bytes);
// Hands the heap's freed pages back to the system (glibc keeps them for
// reuse): between two stages, so the next one's peak is its own, not the sum.
void return_free_memory();

}  // namespace lightstage::pipeline
