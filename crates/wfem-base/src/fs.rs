//! File kinds in error messages: one phrase for each kind of path that is not a regular file,
//! so that a mesh reader, a field reader and the index store say the same thing.

/// What a non-regular file is, for error messages ("a FIFO (named pipe)", "a directory", …).
pub fn file_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}
