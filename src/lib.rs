//! fathom umbrella
