//! The screen: one [`LiveView`] drawn on a ratatui frame.

use gsens_live::{AxisProgress, GENTLER_FRACTION, Instruction, LiveView};
use ratatui::Frame;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols;
use ratatui::text::{Line, Span, Text};
use ratatui::widgets::{Block, Cell, LineGauge, Paragraph, Row, Table, Wrap};

const AXES: [&str; 3] = ["x", "y", "z"];

/// Below this inner width the per-axis table drops its gauge column for a percentage.
const AXES_FULL_WIDTH: u16 = 64;

/// From this width the channels table and the estimate/notices column sit side by side.
const SIDE_BY_SIDE_WIDTH: u16 = 72;

/// Width of the channels table in the side-by-side layout (its columns and borders).
const CHANNELS_WIDTH: u16 = 46;

/// Draws `view` over the whole frame: from the top, the instruction, the
/// progress per axis, the shaking now, the channels beside the latest
/// estimate's trust and the notices, and a status line with the counts
/// received. On a small frame the sections that do not fit are left out,
/// in this order of need: the instruction and the axes are kept longest,
/// then the status line, the shaking, and the rest.
pub fn draw(frame: &mut Frame, view: &LiveView) {
    let area = frame.area();
    if area.is_empty() {
        return;
    }
    let instruction = view.instruction.to_string();
    let instruction_h = wrapped_lines(&instruction, area.width.saturating_sub(2)).saturating_add(2);
    // (wanted, least useful) heights in display order, and the order they are served in.
    let sections: [(u16, u16); 5] = [(instruction_h, 1), (6, 3), (5, 2), (u16::MAX, 5), (1, 1)];
    let priority = [0, 1, 4, 2, 3];
    let mut heights = [0u16; 5];
    let mut left = area.height;
    for i in priority {
        let (want, least) = sections[i];
        let h = want.min(left);
        if h >= least {
            heights[i] = h;
            left -= h;
        }
    }
    let mut y = area.y;
    let mut rects = [Rect::default(); 5];
    for i in 0..5 {
        rects[i] = Rect { x: area.x, y, width: area.width, height: heights[i] };
        y += heights[i];
    }
    let [instr, axes, shaking, lower, status] = rects;
    let buf = frame.buffer_mut();
    draw_instruction(buf, instr, &view.instruction, &instruction);
    draw_axes(buf, axes, view);
    draw_shaking(buf, shaking, view);
    draw_lower(buf, lower, view);
    draw_status(buf, status, view);
}

/// `view` drawn on a `width` × `height` text buffer (ratatui's
/// `TestBackend`), one line per row, trailing blanks trimmed: what the
/// screen shows without its colours.
pub fn render_text(view: &LiveView, width: u16, height: u16) -> String {
    let mut terminal = ratatui::Terminal::new(TestBackend::new(width, height)).expect("a TestBackend never fails");
    let frame = terminal.draw(|f| draw(f, view)).expect("a TestBackend never fails");
    buffer_text(frame.buffer)
}

/// The buffer's symbols, row by row. The screen draws no double-width
/// characters, so every cell is one column of text.
fn buffer_text(buf: &Buffer) -> String {
    let mut out = String::new();
    for y in buf.area.top()..buf.area.bottom() {
        let line: String = (buf.area.left()..buf.area.right()).map(|x| buf[(x, y)].symbol()).collect();
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// Progress of `axis` toward the target σ, in [0, 1]: (target/σ)², since σ
/// falls as 1/√(time shaken), capped at 1; 1 once it meets the target, 0
/// while σ is unknown or the axis unobservable.
pub fn progress_to_target(axis: &AxisProgress, target_sigma_hz_per_mps2: f64) -> f64 {
    if axis.meets_target {
        return 1.0;
    }
    match axis.sigma_hz_per_mps2 {
        Some(sigma) if axis.observable && sigma > 0.0 && sigma.is_finite() && target_sigma_hz_per_mps2 > 0.0 => {
            (target_sigma_hz_per_mps2 / sigma).powi(2).min(1.0)
        }
        _ => 0.0,
    }
}

/// Whether the phase-error gauge shows red: the peak phase error above
/// [`GENTLER_FRACTION`] of the discriminator's linear range, where the
/// instruction says "gentler".
pub fn phase_gauge_is_red(view: &LiveView) -> bool {
    view.peak_phase_rad > GENTLER_FRACTION * view.range_rad
}

/// `x` as a gauge's fill, in [0, 1] (ratatui panics outside it): NaN as empty.
fn gauge_ratio(x: f64) -> f64 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

/// Lines `text` takes when word-wrapped to `width` columns (at least 1).
fn wrapped_lines(text: &str, width: u16) -> u16 {
    let width = usize::from(width.max(1));
    let (mut lines, mut col) = (1u16, 0usize);
    for word in text.split_whitespace() {
        let mut w = word.chars().count();
        let need = if col == 0 { w } else { col + 1 + w };
        if need <= width {
            col = need;
            continue;
        }
        if col > 0 {
            lines = lines.saturating_add(1);
        }
        // A word longer than the line is broken over several.
        while w > width {
            lines = lines.saturating_add(1);
            w -= width;
        }
        col = w;
    }
    lines
}

/// The number of decimals that shows `sigma` with two significant digits.
fn decimals_for(sigma: f64) -> usize {
    if sigma > 0.0 && sigma.is_finite() { (1.0 - sigma.log10().floor()).clamp(0.0, 9.0) as usize } else { 3 }
}

fn instruction_style(instruction: &Instruction) -> Style {
    let color = match instruction {
        Instruction::Waiting => Color::DarkGray,
        Instruction::Rest { .. } => Color::Cyan,
        Instruction::Shake { .. } | Instruction::Next { .. } => Color::LightGreen,
        Instruction::Pace { .. } | Instruction::OneAxis { .. } => Color::Yellow,
        Instruction::Gentler { .. } => Color::LightRed,
        Instruction::Done => Color::Green,
    };
    Style::new().fg(color).add_modifier(Modifier::BOLD)
}

fn draw_instruction(buf: &mut Buffer, area: Rect, instruction: &Instruction, text: &str) {
    if area.is_empty() {
        return;
    }
    let style = instruction_style(instruction);
    let paragraph = Paragraph::new(Span::styled(text.to_string(), style)).wrap(Wrap { trim: true });
    if area.height < 3 {
        render(buf, area, paragraph);
    } else {
        let quit = if area.width >= 50 { " quit: q, Esc, Ctrl-C " } else { " q: quit " };
        let block = Block::bordered()
            .border_style(style)
            .title(" gsens live: do this ")
            .title_top(Line::from(quit).right_aligned());
        render(buf, area, paragraph.block(block));
    }
}

fn render(buf: &mut Buffer, area: Rect, widget: impl ratatui::widgets::Widget) {
    widget.render(area, buf);
}

/// Γ̂ ± σ as text.
fn estimate_text(gamma: Option<f64>, sigma: Option<f64>) -> Option<String> {
    match (gamma, sigma) {
        (Some(g), Some(s)) => {
            let d = decimals_for(s);
            Some(format!("{g:+.d$} ± {s:.d$}"))
        }
        (Some(g), None) => Some(format!("{g:+.5} ± ?")),
        _ => None,
    }
}

/// The streamed Γ̂ ± σ, new at every epoch: "unobservable" when the axis
/// has no stream estimate and the latest batch estimate found it so, "—"
/// before any estimate.
fn gamma_text(view: &LiveView, axis: &AxisProgress) -> String {
    estimate_text(axis.now_gamma_hz_per_mps2, axis.now_sigma_hz_per_mps2)
        .unwrap_or_else(|| if view.batch.is_some() && !axis.observable { "unobservable".into() } else { "—".into() })
}

fn more_text(axis: &AxisProgress) -> String {
    match axis.more_s {
        Some(s) => format!("{:.0}", s.ceil()),
        None => "—".into(),
    }
}

fn draw_axes(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let target = view.target_sigma_hz_per_mps2;
    let target_text = format!("target σ ≤ {:.*} Hz/(m/s²)", decimals_for(target), target);
    let title = if area.width >= 44 { format!(" per axis: {target_text} ") } else { format!(" {target_text} ") };
    let block = Block::bordered().title(title);
    let inner = block.inner(area);
    render(buf, area, block);
    if inner.is_empty() {
        return;
    }
    let full = inner.width >= AXES_FULL_WIDTH;
    let columns: Vec<Constraint> = if full {
        vec![
            Constraint::Length(4),
            Constraint::Length(10),
            Constraint::Length(24),
            Constraint::Fill(1),
            Constraint::Length(12),
        ]
    } else {
        vec![Constraint::Length(4), Constraint::Length(6), Constraint::Fill(1), Constraint::Length(5)]
    };
    let show_header = inner.height >= 4;
    let mut rows = inner.rows();
    if show_header {
        let Some(row) = rows.next() else { return };
        let cells = Layout::horizontal(columns.clone()).spacing(1).split(row);
        let header = if full {
            vec!["axis", "shaken [s]", "Γ̂ ± 1σ now [Hz/(m/s²)]", "progress to the target σ", "more [s]"]
        } else {
            vec!["", "[s]", "Γ̂ ± 1σ [Hz/(m/s²)]", ""]
        };
        let dim = Style::new().add_modifier(Modifier::DIM);
        for (cell, text) in cells.iter().zip(header) {
            render(buf, *cell, Paragraph::new(Span::styled(text, dim)));
        }
    }
    let asked = view.instruction.axis();
    for (i, row) in rows.take(3).enumerate() {
        let a = &view.axes[i];
        let cells = Layout::horizontal(columns.clone()).spacing(1).split(row);
        let marker = if asked == Some(i) { "▶" } else { " " };
        let mut style = Style::new();
        if view.shaking.axis == Some(i) {
            style = style.add_modifier(Modifier::BOLD);
        }
        let met = Style::new().fg(Color::Green).add_modifier(Modifier::BOLD);
        render(buf, cells[0], Paragraph::new(Span::styled(format!("{marker} {}", AXES[i]), style)));
        render(buf, cells[1], Paragraph::new(Span::styled(format!("{:.1}", a.shaken_s), style)));
        render(buf, cells[2], Paragraph::new(Span::styled(gamma_text(view, a), style)));
        let progress = progress_to_target(a, target);
        if full {
            let label = if a.meets_target { "met".to_string() } else { format!("{:3.0}%", 100.0 * progress) };
            let filled = if a.meets_target { met } else { Style::new().fg(Color::Cyan) };
            let gauge = LineGauge::default()
                .ratio(gauge_ratio(progress))
                .label(Span::styled(label, if a.meets_target { met } else { Style::new() }))
                .filled_symbol(symbols::block::FULL)
                .unfilled_symbol(symbols::shade::LIGHT)
                .filled_style(filled)
                .unfilled_style(Style::new().fg(Color::DarkGray));
            render(buf, cells[3], gauge);
            let more = more_text(a);
            let more_style = if a.meets_target { met } else { Style::new() };
            render(buf, cells[4], Paragraph::new(Span::styled(more, more_style)));
        } else {
            let text = if a.meets_target { "met".to_string() } else { format!("{:.0}%", 100.0 * progress) };
            render(buf, cells[3], Paragraph::new(Span::styled(text, if a.meets_target { met } else { style })));
        }
    }
}

fn draw_shaking(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let s = &view.shaking;
    let rms = format!("RMS x {:.2} y {:.2} z {:.2} m/s²", s.rms_mps2[0], s.rms_mps2[1], s.rms_mps2[2]);
    let title = if s.window_s > 0.0 {
        format!(" shaking over the last {:.1} s: {rms} ", s.window_s)
    } else {
        " shaking: no IMU samples yet ".to_string()
    };
    let what = match (s.axis, s.several_axes) {
        (Some(i), _) => Span::styled(format!("{} shaken", AXES[i]), Style::new().add_modifier(Modifier::BOLD)),
        (None, true) => Span::styled("several axes at once", Style::new().fg(Color::Yellow)),
        (None, false) => Span::raw("at rest"),
    };
    // Below three rows: no border, the axis with the RMS, and the phase error.
    let compact = area.height < 3;
    let inner = if compact {
        area
    } else {
        let block = Block::bordered().title(title);
        let inner = block.inner(area);
        render(buf, area, block);
        inner
    };
    if inner.is_empty() {
        return;
    }
    let band = &view.band;
    let mut first = vec![what];
    match s.frequency_hz {
        Some(f) if f > 0.0 && f.is_finite() => {
            let in_band = f >= band.band_hz[0] && f <= band.band_hz[1];
            let (verdict, color) = if in_band { ("in", Color::Green) } else { ("outside", Color::Yellow) };
            first.push(Span::raw(format!(", {f:.2} Hz ({:.2} s per cycle): ", 1.0 / f)));
            first.push(Span::styled(format!("{verdict} the loop's band"), Style::new().fg(color)));
        }
        _ if s.axis.is_some() => first.push(Span::raw(", frequency: none measured yet")),
        _ => {}
    }
    if compact {
        first.push(Span::raw(format!(" · {rms}")));
    }
    let aim = Line::from(format!(
        "loop: half-power band {:.2}–{:.2} Hz, peak {:.2} Hz: aim at {:.2} s per cycle",
        band.band_hz[0],
        band.band_hz[1],
        band.peak_hz,
        band.period_s()
    ));
    let lines = if compact { Text::from(Line::from(first)) } else { Text::from(vec![Line::from(first), aim]) };
    let [text_area, phase_area] = Layout::vertical([Constraint::Fill(1), Constraint::Length(1)]).areas(inner);
    let (text_area, phase_area) =
        if inner.height >= 3 || compact { (text_area, phase_area) } else { (inner, Rect::default()) };
    render(buf, text_area, Paragraph::new(lines));
    if phase_area.is_empty() {
        return;
    }
    let red = phase_gauge_is_red(view);
    let ratio = if view.range_rad > 0.0 { gauge_ratio(view.peak_phase_rad / view.range_rad) } else { 0.0 };
    let label = if phase_area.width >= 90 {
        format!("phase error: peak {:.2} rad of the discriminator's {:.2} rad", view.peak_phase_rad, view.range_rad)
    } else {
        format!("phase error peak {:.2} of {:.2} rad", view.peak_phase_rad, view.range_rad)
    };
    let color = if red { Color::Red } else { Color::Green };
    let label_style = if red { Style::new().fg(Color::Red).add_modifier(Modifier::BOLD) } else { Style::new() };
    let gauge = LineGauge::default()
        .ratio(ratio)
        .label(Span::styled(label, label_style))
        .filled_symbol(symbols::block::FULL)
        .unfilled_symbol(symbols::shade::LIGHT)
        .filled_style(Style::new().fg(color))
        .unfilled_style(Style::new().fg(Color::DarkGray));
    render(buf, phase_area, gauge);
}

fn draw_lower(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    // The notices box holds up to four wrapped lines of the latest notices.
    let notices_h = |width: u16| {
        let inner_w = width.saturating_sub(2);
        let lines = view.notices.0.iter().map(|n| wrapped_lines(n, inner_w)).fold(0, u16::saturating_add);
        2 + lines.clamp(1, 4)
    };
    if area.width >= SIDE_BY_SIDE_WIDTH {
        let [channels, right] =
            Layout::horizontal([Constraint::Length(CHANNELS_WIDTH), Constraint::Fill(1)]).areas(area);
        let [batch, notices] =
            Layout::vertical([Constraint::Fill(1), Constraint::Length(notices_h(right.width))]).areas(right);
        draw_channels(buf, channels, view);
        draw_batch(buf, batch, view);
        draw_notices(buf, notices, view);
    } else {
        let channels_h = 3 + (view.channels.len().max(1) as u16);
        let [channels, batch, notices] =
            Layout::vertical([Constraint::Max(channels_h), Constraint::Min(3), Constraint::Max(notices_h(area.width))])
                .areas(area);
        draw_channels(buf, channels, view);
        draw_batch(buf, batch, view);
        draw_notices(buf, notices, view);
    }
}

fn draw_channels(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let channels = &view.channels;
    let tracking = channels.iter().filter(|c| c.tracking).count();
    // Rows that fit under the border and the header.
    let room = usize::from(area.height.saturating_sub(3));
    let hidden = channels.len().saturating_sub(room);
    let title = if hidden > 0 {
        format!(" channels: {tracking} of {} tracking, {hidden} not shown ", channels.len())
    } else {
        format!(" channels: {tracking} of {} tracking ", channels.len())
    };
    let header =
        Row::new(["ch", "PRN", "C/N0 [dB-Hz]", "φ [rad]", "state"]).style(Style::new().add_modifier(Modifier::DIM));
    let rows: Vec<Row> = if channels.is_empty() {
        let none = match &view.ubx {
            // A UBX stream has no tracking rows: its tracks are in the status line.
            Some(_) => "a UBX stream: its tracks below",
            None => "no tracking rows yet",
        };
        vec![Row::new([Cell::from(none)])]
    } else {
        channels
            .iter()
            .map(|c| {
                let state = if c.tracking {
                    Cell::from(Span::styled("tracking", Style::new().fg(Color::Green)))
                } else {
                    Cell::from(Span::styled("lost", Style::new().fg(Color::Red).add_modifier(Modifier::BOLD)))
                };
                Row::new([
                    Cell::from(c.channel.to_string()),
                    Cell::from(c.prn.to_string()),
                    Cell::from(format!("{:.1}", c.cn0_dbhz)),
                    Cell::from(format!("{:+.3}", c.phase_err_rad)),
                    state,
                ])
            })
            .collect()
    };
    let widths = if channels.is_empty() {
        vec![Constraint::Fill(1)]
    } else {
        vec![
            Constraint::Length(3),
            Constraint::Length(4),
            Constraint::Length(12),
            Constraint::Length(8),
            Constraint::Fill(1),
        ]
    };
    let table = Table::new(rows, widths).header(header).block(Block::bordered().title(title));
    render(buf, area, table);
}

/// "loop-free " for an estimate from the input phase: the checked estimate
/// is otherwise the one through the loop model.
fn loop_free_label(measurement: gsens_calib::Measurement) -> &'static str {
    if measurement == gsens_calib::Measurement::InputPhase { "loop-free " } else { "" }
}

fn draw_batch(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let title = match &view.batch {
        Some(b) => format!(" checked {}estimate on data to {:.1} s ", loop_free_label(b.measurement), b.data_end_s),
        None => " checked estimate ".to_string(),
    };
    let block = Block::bordered().title(title);
    let mut lines = Vec::new();
    match (&view.batch, &view.batch_error) {
        (Some(b), _) => {
            let warnings = &b.warnings;
            let verdict = if b.trustworthy {
                Span::styled("TRUSTWORTHY", Style::new().fg(Color::Green).add_modifier(Modifier::BOLD))
            } else {
                Span::styled("NOT TRUSTWORTHY", Style::new().fg(Color::Red).add_modifier(Modifier::BOLD))
            };
            lines.push(Line::from(verdict));
            for (name, a) in AXES.iter().zip(&view.axes) {
                let text = match estimate_text(a.gamma_hz_per_mps2, a.sigma_hz_per_mps2) {
                    Some(t) if a.observable => t,
                    _ => "unobservable".into(),
                };
                lines.push(Line::from(format!("{name} {text}")));
            }
            if warnings.is_empty() {
                lines.push(Line::from("no warnings"));
            }
            for w in warnings {
                lines.push(Line::from(Span::styled(
                    format!("- {}: {}", w.code, w.message),
                    Style::new().fg(Color::Yellow),
                )));
            }
        }
        (None, Some(error)) => {
            lines.push(Line::from(Span::styled("failed:", Style::new().fg(Color::Red).add_modifier(Modifier::BOLD))));
            lines.push(Line::from(error.as_str()));
        }
        (None, None) => lines.push(Line::from("none yet: the first runs once enough data arrived")),
    }
    render(buf, area, Paragraph::new(lines).wrap(Wrap { trim: true }).block(block));
}

fn draw_notices(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let (latest, total) = &view.notices;
    let block = Block::bordered().title(format!(" notices: {total} in all "));
    let inner = block.inner(area);
    // The most recent last, as many whole notices as fit (the newest alone,
    // its end in view, when even it does not).
    let (mut shown, mut used) = (0usize, 0u16);
    for n in latest.iter().rev() {
        let h = wrapped_lines(n, inner.width);
        if shown > 0 && used.saturating_add(h) > inner.height {
            break;
        }
        used = used.saturating_add(h);
        shown += 1;
    }
    let lines: Vec<Line> = if latest.is_empty() {
        vec![Line::from("none")]
    } else {
        latest[latest.len() - shown..].iter().map(|n| Line::from(n.as_str())).collect()
    };
    let scroll = used.saturating_sub(inner.height);
    render(buf, area, Paragraph::new(lines).wrap(Wrap { trim: true }).scroll((scroll, 0)).block(block));
}

fn draw_status(buf: &mut Buffer, area: Rect, view: &LiveView) {
    if area.is_empty() {
        return;
    }
    let (imu, tracking) = view.received;
    let text = match &view.ubx {
        Some(u) => format!("data {:.1} s · received {imu} IMU samples · UBX: {}", view.data_s, u.summary()),
        None => format!("data {:.1} s · received {imu} IMU samples, {tracking} tracking rows", view.data_s),
    };
    render(buf, area, Paragraph::new(Span::styled(text, Style::new().add_modifier(Modifier::DIM))));
}
