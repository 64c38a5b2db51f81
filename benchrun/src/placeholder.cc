// Replaced by the reader and writer.
