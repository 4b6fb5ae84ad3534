//! The cheapest scheme and lowest rate whose discretisation error stays below a fraction of
//! the noise-induced standard deviation: every (scheme, rate) evaluated ([`candidates`]).

pub mod candidates;

pub use candidates::*;
