//! The terminal UI of `blockstack demo` (ratatui + crossterm).
//!
//! [`app`] is the state machine (keys and ticks, no terminal), [`view`] draws it; [`run`]
//! connects them to a real terminal.

pub mod app;
pub mod view;

use std::time::{Duration, Instant};

use agent::DemoSink;
use anyhow::{Context, Result};
use ratatui::DefaultTerminal;
use ratatui::crossterm::event::{self, Event};
use ratatui::layout::Size;

use app::{Command, DemoApp, command_for};

/// Runs `app` in the terminal until the person quits: draws, reads keys, and lets the agent
/// step at its pace. The terminal is restored however this ends.
pub fn run<S: DemoSink>(app: &mut DemoApp<S>) -> Result<()> {
    let mut terminal = ratatui::try_init().context("blockstack demo needs an interactive terminal")?;
    let outcome = event_loop(&mut terminal, app);
    ratatui::restore();
    outcome
}

fn event_loop<S: DemoSink>(terminal: &mut DefaultTerminal, app: &mut DemoApp<S>) -> Result<()> {
    let blocks = app.agent().blocks();
    let grid = app.agent().grid();
    let mut last_tick = Instant::now();
    while !app.should_quit() {
        // A terminal too small to show the world stops the agent until it grows.
        app.set_hidden(!view::fits(terminal.size()?, grid, blocks));
        terminal.draw(|frame| view::draw(frame, app))?;
        let wait = app.tick_interval().saturating_sub(last_tick.elapsed());
        if event::poll(wait.min(Duration::from_millis(250)))? {
            match event::read()? {
                Event::Key(key) => {
                    if let Some(command) = command_for(key, blocks) {
                        app.handle(command)?;
                        if matches!(command, Command::Override(_) | Command::NextEpisode) {
                            // The agent waits a full beat after the person acts.
                            last_tick = Instant::now();
                        }
                    }
                }
                // Before the agent's next step, not at the next redraw.
                Event::Resize(width, height) => app.set_hidden(!view::fits(Size { width, height }, grid, blocks)),
                // Any other event just redraws.
                _ => {}
            }
        }
        if last_tick.elapsed() >= app.tick_interval() {
            app.tick()?;
            last_tick = Instant::now();
        }
    }
    Ok(())
}
