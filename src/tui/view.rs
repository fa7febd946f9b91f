//! Drawing `blockstack demo`: the grid with each block in its colour (the held block in
//! brackets), the goal as a small stack in the top-right corner as the paper's screen has
//! it, the step count, the agent's proposal, and a help line.

use agent::DemoSink;
use ratatui::Frame;
use ratatui::layout::{Alignment, Constraint, Layout, Rect, Size};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Padding, Paragraph, Wrap};
use sim::render::{colour, label};
use sim::{BlockId, Cell, Grid, Observation};

use super::app::DemoApp;

/// Width of the panel beside the grid.
const PANEL_WIDTH: u16 = 36;

/// Lines the panel needs.
const PANEL_HEIGHT: u16 = 13;

/// Width of the goal's box in the top-right corner.
const GOAL_BOX_WIDTH: u16 = 9;

/// The help line for a world of `blocks` blocks (their labels pick them).
pub fn help(blocks: usize) -> String {
    let picks = match blocks {
        ..=10 => format!("0-{} pick", label(BlockId::of(blocks - 1))),
        _ => format!("0-9 A-{} pick", label(BlockId::of(blocks - 1))),
    };
    format!("arrows move  {picks}  d drop  space pause  +/- pace  n next  q quit")
}

/// A grid cell's size on screen: columns and rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct CellSize {
    width: u16,
    height: u16,
}

/// Roomy cells, then compact ones.
const CELL_SIZES: [CellSize; 2] = [CellSize { width: 4, height: 2 }, CellSize { width: 3, height: 1 }];

/// The terminal size a layout with `cell` needs for `grid` and `blocks`: the grid in a
/// box, the panel beside it, a title line above and the help line below.
fn needed(grid: Grid, blocks: usize, cell: CellSize) -> (u16, u16) {
    let w = grid.width() as u16 * cell.width + 2 + PANEL_WIDTH;
    let h = (grid.height() as u16 * cell.height + 2).max(PANEL_HEIGHT) + 2;
    (w.max(help(blocks).len() as u16), h)
}

/// The smallest terminal `blockstack demo` works in for `grid` and `blocks` (3 blocks on
/// 7 x 7: 61 x 19, so 80 x 24 is plenty).
pub fn minimum_size(grid: Grid, blocks: usize) -> (u16, u16) {
    needed(grid, blocks, CELL_SIZES[CELL_SIZES.len() - 1])
}

/// The cell size the screen `area` shows `grid` with, if it is large enough.
fn cell_size(area: Size, grid: Grid, blocks: usize) -> Option<CellSize> {
    CELL_SIZES.into_iter().find(|&c| {
        let (w, h) = needed(grid, blocks, c);
        area.width >= w && area.height >= h
    })
}

/// Whether a terminal of `area` shows the world of `grid` and `blocks`: if not, it gets a
/// polite message and the agent waits ([`DemoApp::set_hidden`]).
pub fn fits(area: Size, grid: Grid, blocks: usize) -> bool {
    cell_size(area, grid, blocks).is_some()
}

/// Draws the whole screen.
pub fn draw<S: DemoSink>(frame: &mut Frame, app: &DemoApp<S>) {
    let area = frame.area();
    let grid = app.agent().grid();
    let blocks = app.agent().blocks();
    let Some(cell) = cell_size(area.as_size(), grid, blocks) else {
        draw_too_small(frame, grid, blocks);
        return;
    };
    let [title, body, help_area] =
        Layout::vertical([Constraint::Length(1), Constraint::Min(0), Constraint::Length(1)]).areas(area);
    let grid_box = grid.width() as u16 * cell.width + 2;
    let [world, panel] = Layout::horizontal([Constraint::Length(grid_box), Constraint::Min(0)]).areas(body);
    let session = app.session();
    let obs = session.observation();
    let episode = session.episode_number().map_or(0, |k| k + 1);
    frame.render_widget(
        Paragraph::new(Line::from(vec![
            Span::styled(" blockstack demo ", Style::new().add_modifier(Modifier::BOLD)),
            Span::raw(format!(
                " episode {episode}  step {}  corrections {}",
                session.steps(),
                session.report().corrections
            )),
        ])),
        title,
    );
    if let Some(obs) = obs {
        let world = Rect {
            height: world.height.min(grid.height() as u16 * cell.height + 2),
            ..world
        };
        frame.render_widget(
            // In the side view the box's bottom edge is the table row 0 stands on.
            Paragraph::new(grid_lines(&obs, cell)).block(Block::bordered().title(match obs.view {
                sim::View::Top => " world ",
                sim::View::Side => " world, side view ",
            })),
            world,
        );
        let [info, corner] =
            Layout::horizontal([Constraint::Min(0), Constraint::Length(goal_box_width(&obs))]).areas(panel);
        let tallest = obs.goal.towers().map(|t| t.len()).max().unwrap_or(0);
        let corner = Rect {
            height: corner.height.min(tallest as u16 + 2),
            ..corner
        };
        frame.render_widget(
            Paragraph::new(goal_lines(&obs)).block(Block::bordered().title(" goal ")),
            corner,
        );
        frame.render_widget(
            Paragraph::new(panel_lines(app, &obs))
                .wrap(Wrap { trim: true })
                .block(Block::new().padding(Padding::horizontal(1))),
            info,
        );
    }
    frame.render_widget(
        Paragraph::new(help(blocks)).style(Style::new().add_modifier(Modifier::REVERSED)),
        help_area,
    );
}

/// The polite message for a terminal too small for even the compact layout.
fn draw_too_small(frame: &mut Frame, grid: Grid, blocks: usize) {
    let area = frame.area();
    let (w, h) = minimum_size(grid, blocks);
    let text = vec![
        Line::from("Sorry, this terminal is too small for blockstack demo."),
        Line::from(format!(
            "It is {}x{}; please make it at least {w}x{h} (80x24 is fine).",
            area.width, area.height
        )),
        Line::from("The agent waits until it is. q quits."),
    ];
    frame.render_widget(
        Paragraph::new(text)
            .alignment(Alignment::Center)
            .wrap(Wrap { trim: true }),
        area,
    );
}

/// The colour of `block` on screen.
fn block_colour(block: BlockId) -> Color {
    let [r, g, b] = colour(block);
    Color::Rgb(r, g, b)
}

/// The grid, top row first: a block is its label on its colour, the held one in brackets.
fn grid_lines(obs: &Observation, cell: CellSize) -> Vec<Line<'static>> {
    let (w, h) = (obs.grid.width() as u16, obs.grid.height() as u16);
    let width = cell.width as usize;
    let mut lines = Vec::new();
    for y in (0..h).rev() {
        for row in 0..cell.height {
            let spans: Vec<Span> = (0..w)
                .map(|x| match obs.state.block_at(Cell::new(x, y)) {
                    Some(b) => {
                        let text = if row + 1 < cell.height {
                            " ".repeat(width)
                        } else if obs.held_block() == Some(b) {
                            format!("{:<width$}", format!("[{}]", label(b)))
                        } else {
                            format!("{:<width$}", format!(" {}", label(b)))
                        };
                        let mut style = Style::new()
                            .bg(block_colour(b))
                            .fg(Color::White)
                            .add_modifier(Modifier::BOLD);
                        if obs.held_block() == Some(b) {
                            style = style.add_modifier(Modifier::UNDERLINED);
                        }
                        Span::styled(text, style)
                    }
                    None if row + 1 == cell.height => {
                        Span::styled(format!("{:<width$}", " ."), Style::new().fg(Color::DarkGray))
                    }
                    None => Span::raw(" ".repeat(width)),
                })
                .collect();
            lines.push(Line::from(spans));
        }
    }
    lines
}

/// The goal as small stacks side by side, top blocks first: one for each tower.
fn goal_lines(obs: &Observation) -> Vec<Line<'static>> {
    let towers: Vec<&[BlockId]> = obs.goal.towers().collect();
    let height = towers.iter().map(|t| t.len()).max().unwrap_or(0);
    (0..height)
        .rev()
        .map(|row| {
            let mut spans = vec![Span::raw("  ")];
            for tower in &towers {
                spans.push(match tower.get(row) {
                    Some(&b) => Span::styled(
                        format!(" {} ", label(b)),
                        Style::new().bg(block_colour(b)).fg(Color::White),
                    ),
                    None => Span::raw("   "),
                });
                spans.push(Span::raw(" "));
            }
            Line::from(spans)
        })
        .collect()
}

/// The goal box's width: one tower's room per tower (the box holds one at least).
fn goal_box_width(obs: &Observation) -> u16 {
    GOAL_BOX_WIDTH.max(obs.goal.tower_count() as u16 * 4 + 3)
}

/// The panel's figures.
fn panel_lines<S: DemoSink>(app: &DemoApp<S>, obs: &Observation) -> Vec<Line<'static>> {
    let session = app.session();
    let mut lines = vec![Line::from(Span::styled(
        format!("goal {} (bottom to top)", obs.goal),
        Style::new().add_modifier(Modifier::BOLD),
    ))];
    lines.push(Line::from(""));
    let held = obs.held_block().map_or("none".to_string(), |b| label(b).to_string());
    lines.push(Line::from(format!("held: {held}")));
    lines.push(Line::from(format!("step: {}", session.steps())));
    let proposal = match session.proposal() {
        Some(a) => a.to_string(),
        None if obs.goal.holds(&obs.state) => "- (goal reached)".into(),
        None => "- (episode over)".into(),
    };
    lines.push(Line::from(vec![
        Span::raw("agent proposes: "),
        Span::styled(proposal, Style::new().add_modifier(Modifier::BOLD)),
    ]));
    let pace = if app.is_paused() {
        "PAUSED".to_string()
    } else {
        format!("{} steps/s", app.pace())
    };
    lines.push(Line::from(format!("pace: {pace}")));
    lines.push(Line::from(format!(
        "corrections: {} (this episode {})",
        session.report().corrections,
        app.episode_corrections()
    )));
    lines.push(Line::from(""));
    lines.push(Line::from(app.message().to_string()));
    lines
}

#[cfg(test)]
mod tests {
    use super::super::app::Command;
    use super::super::app::tests::{app, tempdir};
    use super::*;
    use ratatui::Terminal;
    use ratatui::backend::TestBackend;
    use sim::Action;

    /// The screen as text, one line per row.
    fn screen<S: DemoSink>(app: &DemoApp<S>, width: u16, height: u16) -> String {
        let mut terminal = Terminal::new(TestBackend::new(width, height)).unwrap();
        terminal.draw(|f| draw(f, app)).unwrap();
        let buffer = terminal.backend().buffer();
        buffer
            .content()
            .chunks(buffer.area.width as usize)
            .map(|row| row.iter().map(|c| c.symbol()).collect::<String>())
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn an_80x24_screen_shows_the_grid_the_goal_the_proposal_and_the_help() {
        let dir = tempdir();
        let app = app(dir.path());
        let text = screen(&app, 80, 24);
        assert!(text.contains("goal 1,0,2"), "{text}");
        assert!(text.contains("world"));
        assert!(text.contains("agent proposes: "));
        assert!(text.contains("held: none"));
        assert!(text.contains("q quit"));
        // Every block's label shows, on a grid of 7 rows of cells.
        let obs = app.session().observation().unwrap();
        for b in obs.state.blocks() {
            assert!(text.contains(&format!(" {}", label(b))));
        }
        assert!(text.lines().filter(|l| l.contains(" .")).count() >= 7);
    }

    #[test]
    fn the_held_block_is_marked_and_the_step_count_moves() {
        let dir = tempdir();
        let mut app = app(dir.path());
        app.handle(Command::TogglePause).unwrap();
        app.handle(Command::Override(Action::Pick(BlockId(2)))).unwrap();
        let text = screen(&app, 80, 24);
        assert!(text.contains("[2]"), "{text}");
        assert!(text.contains("held: 2"));
        assert!(text.contains("step: 1"));
        assert!(text.contains("PAUSED"));
        assert!(text.contains("instead of") || text.contains("confirmed"));
    }

    #[test]
    fn a_small_terminal_gets_a_polite_message_and_a_middling_one_the_compact_grid() {
        let dir = tempdir();
        let app = app(dir.path());
        let text = screen(&app, 50, 12);
        assert!(text.contains("too small"), "{text}");
        assert!(text.contains("50x12"));
        let (w, h) = minimum_size(Grid::default(), 3);
        assert!(w <= 80 && h <= 24);
        let text = screen(&app, w, h);
        assert!(!text.contains("too small"), "{text}");
        assert!(text.contains("goal 1,0,2"));
    }

    #[test]
    fn the_side_view_is_named_and_a_goal_of_towers_drawn_tower_by_tower() {
        let dir = tempdir();
        let app = crate::tui::app::tests::side_app(dir.path());
        let text = screen(&app, 80, 24);
        assert!(text.contains("world, side view"), "{text}");
        assert!(text.contains("goal 0,1/2"), "{text}");
        // Tower 0,1 and tower 2 side by side: 2 on the bottom row beside 0, 1 above 0.
        assert!(text.lines().any(|l| l.contains(" 0   2 ")), "{text}");
        assert!(text.lines().any(|l| l.contains(" 1     ")), "{text}");
    }
}
