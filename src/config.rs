//! Server settings and limits: one struct, documented defaults, settable by flags or environment.
