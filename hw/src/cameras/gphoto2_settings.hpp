#pragma once
// The text side of a gphoto2 camera's settings, apart from the library so that
// it is testable without a camera: which configuration widgets hold a setting
// on which camera family, how their choice strings read as numbers, and which
// choice is nearest to what was asked.
//
// libgphoto2 offers each setting as a radio widget with the camera's own
// strings: shutter speeds such as "1/8000", "1/3", "0.3", "1\"3", "30",
// "30\"", "bulb"; apertures "f/5.6" or "5.6"; ISO "100", "Auto", "Hi 1".

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace lightstage::hw::gphoto2 {

enum class Setting { kShutter, kIso, kAperture, kImageFormat, kCaptureTarget };

std::string_view to_string(Setting setting);  // "shutter speed", "ISO", ...

// The widget names that hold `setting`, in the order to try them (Canon and
// Nikon "shutterspeed", Nikon's "shutterspeed2", Sony's "exposuretime", ...).
std::span<const std::string_view> widget_names(Setting setting);

// A shutter-speed choice in microseconds: "1/8000" (a fraction of a second),
// "0.3", "2", "30" (seconds), "1\"3" (1.3 s, the camera's display style),
// "30\"", "2s", "1/125s". nullopt for "bulb", "time", "auto" and anything
// else that is not a fixed duration.
std::optional<double> parse_shutter_us(std::string_view text);

// An aperture choice: "f/5.6", "F8", "5.6", "f/8.0" -> 5.6, 8, 5.6, 8.
// nullopt for "implicit auto", "---" and the like.
std::optional<double> parse_f_number(std::string_view text);

// An ISO choice: "100", "ISO 100", "6400" -> the number. nullopt for "Auto",
// "Auto ISO", "Hi 1", "Lo 1" and other choices that are no fixed speed.
std::optional<double> parse_iso(std::string_view text);

// The index of the choice whose value (by `parse`) is nearest to `wanted` in
// log space, never one that `parse` refuses (bulb, auto). nullopt when no
// choice is within `max_log2_ratio` of `wanted` (e.g. 0.5: half a stop of
// exposure; 0.25 for an f-number, whose stop is a factor of sqrt 2).
std::optional<std::size_t> nearest_choice(const std::vector<std::string>& choices, double wanted,
                                          std::optional<double> (*parse)(std::string_view),
                                          double max_log2_ratio);

// How far, in stops of exposure, `a` may be from `b` for each numeric setting.
double max_log2_ratio(Setting setting);

// The index of the choice named `wanted`: an exact match ignoring case first,
// else the shortest choice that holds `wanted` as a case-insensitive
// substring ("RAW" picks "RAW" over "RAW + Large Fine JPEG"). nullopt when
// none holds it.
std::optional<std::size_t> choice_by_name(const std::vector<std::string>& choices, std::string_view wanted);

// The capture-target choice that keeps files on the memory card ("Memory
// card", "card", "Card"), when there is one.
std::optional<std::size_t> memory_card_choice(const std::vector<std::string>& choices);

// The choices for an error message: "1/8000, 1/6400, ..., 30" (the first and
// last few when there are many).
std::string describe_choices(const std::vector<std::string>& choices);

// A shutter speed for people: 125 -> "1/8000 s", 300000 -> "0.3 s".
std::string describe_shutter_us(double us);

}  // namespace lightstage::hw::gphoto2
