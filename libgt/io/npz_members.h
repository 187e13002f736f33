// The members of a .npz as their .npy bytes, not parsed: for members of a dtype that ParseNpy
// (npy.h) does not take, such as NumPy strings ('<U<n>', the frame ids of a covisibility
// graph), read with ParseNpyHeader. Implemented in npy.cc, beside ReadNpz (same checks of the
// archive and its members, same messages).
#pragma once

#include <map>
#include <string>

namespace gt::io {

// Member name without ".npy" → the member's bytes. Throws InputError naming the file.
std::map<std::string, std::string> ReadNpzBytes(const std::string& path);

}  // namespace gt::io
