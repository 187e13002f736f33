// Transitional: include the header of the concern instead (file_read.h, atomic_file.h,
// md5.h, text_parsing.h). Removed once every include is moved.
#pragma once

#include "libgt/io/atomic_file.h"
#include "libgt/io/file_read.h"
#include "libgt/io/md5.h"
#include "libgt/io/text_parsing.h"
