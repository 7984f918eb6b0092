//! Payload estimation (32)–(35).
