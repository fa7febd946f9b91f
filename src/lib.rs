pub use sim;
