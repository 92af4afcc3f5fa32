#pragma once
// The idle screen of a persistent wall (the wall service): what every display shows between
// render jobs and before the first. The display's name large in the middle, a few smaller lines
// below it (the wall's address, a status), on a dark background whose gradient and thin border
// make each display's edges visible on the wall.
//
// Text is drawn with FreeType (anti-aliased, DejaVu Sans from Debian's fonts-dejavu-core). The
// font files are opened once per process and kept, behind a mutex: safe to call from several
// threads (their FreeType parts run one at a time; the pixels are filled outside the lock).
#include <string>
#include <vector>

#include "wall/image/Image.h"

namespace wall {

struct IdleText {
  std::string title;               // the display's name, drawn large (UTF-8)
  std::vector<std::string> lines;  // smaller lines below it, one per entry (UTF-8)
};

// The TrueType files the idle screen draws with: the title in `bold`, the lines in `regular`
// (either stands in for the other when only one of them can be opened). Defaults: DejaVu Sans
// as fonts-dejavu-core installs it.
struct IdleFonts {
  std::string regular = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  std::string bold = "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf";
};

// An opaque RGBA8 image of `width` x `height` (both > 0, else throws base::Error). The title is
// about 1/8 of the height, the lines about 1/24 (at least 10 px); the whole text is centred and
// shrunk until it fits inside a margin (a line too wide gets smaller, never cut). On a display too
// small for legible text (a few pixels high) the lines and then the title are left out. The same
// input gives the same pixels. Input that is not valid UTF-8 shows U+FFFD for the bad bytes.
//
// When a font file cannot be opened the image still comes back (without the text that needed
// it) and `warning`, if given, names the file and the Debian package that installs it; when
// every font opened, `*warning` is set empty.
Image renderIdleScreen(int width, int height, const IdleText& text, std::string* warning = nullptr);
Image renderIdleScreen(int width, int height, const IdleText& text, const IdleFonts& fonts,
                       std::string* warning = nullptr);

}  // namespace wall
