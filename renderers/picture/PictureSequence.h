#pragma once
// Which files `dfbwall show` plays, and which of them a frame shows.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace renderers::picture {

// The files `arguments` name, in order. A name with one number field (%d, or %0Nd for N-digit
// zero-padded numbers, as printf writes them; %% is a literal %) is a numbered sequence: every
// file of its folder it names, from the lowest number to the highest, each number once. Throws
// base::Error naming the argument: a file that does not exist, a sequence that matches no file,
// a sequence with a gap (naming the first missing file), a second number field.
std::vector<std::string> expandPictures(const std::vector<std::string>& arguments);

// The index of the file frame `frameId` (1, 2, ...) shows among `count`: frame k+1 shows file
// k; past the last, `loop` starts again from the first, else the last stays.
std::size_t pictureOfFrame(std::uint32_t frameId, std::size_t count, bool loop);

}  // namespace renderers::picture
