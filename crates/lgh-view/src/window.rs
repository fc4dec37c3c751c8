//! The window: winit's event loop on the main thread takes the input and presents the last
//! finished frame through softbuffer; a worker thread owns the frame loop and renders one
//! frame after another, so the window stays responsive however long a frame takes.

use std::num::NonZeroU32;
use std::rc::Rc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::sync::{Arc, Mutex};

use anyhow::{Result, anyhow};
use lgh_scene::Scene;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop, EventLoopProxy};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::ViewArgs;
use crate::headless::{Record, finish, script_step, start};
use crate::overlay;
use crate::state::{Action, action_of_key};

/// What the worker tells the event loop.
#[derive(Debug)]
enum Note {
    /// A new frame is in the shared slot.
    Frame,
    /// The worker is done (frame limit, or an error as text).
    Done(Option<String>),
}

/// The pixels of the frame the worker finished last, with its readout
/// ([`crate::overlay::readout`]).
type Slot = Arc<Mutex<Option<(Vec<u32>, Vec<String>)>>>;

/// Prints the controls.
pub fn print_help() {
    eprint!("{}", crate::state::controls_help());
}

/// Opens the window over `scene` and runs until it is closed or `--frames` are shown.
///
/// # Errors
/// No display, bad settings, or a failed frame.
pub fn run(args: ViewArgs, scene: Scene) -> Result<()> {
    let event_loop = EventLoop::<Note>::with_user_event()
        .build()
        .map_err(|e| anyhow!("cannot open a window ({e}); try --headless"))?;
    let (engine, state) = start(&args, scene)?;
    let (tx, rx) = channel::<Action>();
    let slot: Slot = Arc::new(Mutex::new(None));
    let proxy = event_loop.create_proxy();
    let worker_slot = Arc::clone(&slot);
    let args = Arc::new(args);
    let worker_args = Arc::clone(&args);
    let worker = std::thread::spawn(move || {
        let result = work(&worker_args, engine, state, &rx, &worker_slot, &proxy);
        let _ = proxy.send_event(Note::Done(result.err().map(|e| format!("{e:#}"))));
    });
    print_help();
    let mut app = App {
        size: args.size,
        show_help: false,
        show_readout: true,
        window: None,
        surface: None,
        actions: tx,
        slot,
        dragging: false,
        cursor: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window: {e}"))?;
    drop(app.actions);
    let _ = worker.join();
    match app.error {
        Some(e) => Err(anyhow!(e)),
        None => Ok(()),
    }
}

/// The worker: applies the actions and the script, renders, publishes, until the frame limit
/// or until the window closes (the action channel hangs up).
fn work(
    args: &ViewArgs,
    mut engine: crate::engine::FrameLoop,
    mut state: crate::state::ViewState,
    actions: &Receiver<Action>,
    slot: &Slot,
    proxy: &EventLoopProxy<Note>,
) -> Result<()> {
    let mut record = Record::default();
    record.start();
    let mut frame = 0u64;
    loop {
        loop {
            match actions.try_recv() {
                Ok(a) => {
                    if let Some(line) = state.apply(a) {
                        eprintln!("{line}");
                    }
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    return finish(args, &state, &record);
                }
            }
        }
        script_step(args, &mut state, frame);
        let shown = engine.render(&state)?;
        state.saw(&shown);
        let lines = overlay::readout(&shown, &state);
        if let Ok(mut s) = slot.lock() {
            *s = Some((shown.pixels.clone(), lines));
        }
        record.push(shown);
        frame += 1;
        if proxy.send_event(Note::Frame).is_err() {
            return finish(args, &state, &record);
        }
        if args.frames.is_some_and(|n| frame >= n) {
            return finish(args, &state, &record);
        }
    }
}

struct App {
    size: (u32, u32),
    /// The help overlay is shown (H).
    show_help: bool,
    /// The readout is shown (O).
    show_readout: bool,
    window: Option<Rc<Window>>,
    surface: Option<softbuffer::Surface<Rc<Window>, Rc<Window>>>,
    actions: Sender<Action>,
    slot: Slot,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    error: Option<String>,
}

impl App {
    /// Copies the last frame to the window, scaled to its size (nearest pixel), with the
    /// readout and the help drawn over it.
    fn present(&mut self) {
        let (Some(window), Some(surface)) = (&self.window, &mut self.surface) else {
            return;
        };
        let Some((pixels, lines)) = self.slot.lock().ok().and_then(|s| s.clone()) else {
            return;
        };
        window.set_title(&format!(
            "lgh view | {}",
            lines.first().map_or("", String::as_str)
        ));
        let size = window.inner_size();
        let (Some(w), Some(h)) = (NonZeroU32::new(size.width), NonZeroU32::new(size.height)) else {
            return;
        };
        if surface.resize(w, h).is_err() {
            return;
        }
        let Ok(mut buffer) = surface.buffer_mut() else {
            return;
        };
        let (fw, fh) = (self.size.0 as usize, self.size.1 as usize);
        let (ww, wh) = (size.width as usize, size.height as usize);
        if pixels.len() == fw * fh {
            for y in 0..wh {
                let sy = y * fh / wh;
                for x in 0..ww {
                    buffer[y * ww + x] = pixels[sy * fw + x * fw / ww];
                }
            }
        }
        let scale = overlay::scale_for(wh);
        let mut y = 0;
        if self.show_readout {
            y = overlay::draw(&mut buffer, ww, wh, (0, 0), &lines, scale);
        }
        if self.show_help {
            overlay::draw(&mut buffer, ww, wh, (0, y), &overlay::help(), scale);
        }
        let _ = buffer.present();
    }
}

impl ApplicationHandler<Note> for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attrs = Window::default_attributes()
            .with_title("lgh view")
            .with_inner_size(winit::dpi::PhysicalSize::new(self.size.0, self.size.1));
        let made = event_loop.create_window(attrs).map(Rc::new).map(|w| {
            let context = softbuffer::Context::new(Rc::clone(&w));
            (w, context)
        });
        match made {
            Ok((w, Ok(context))) => match softbuffer::Surface::new(&context, Rc::clone(&w)) {
                Ok(surface) => {
                    self.surface = Some(surface);
                    self.window = Some(w);
                }
                Err(e) => {
                    self.error = Some(format!("cannot draw in the window: {e}"));
                    event_loop.exit();
                }
            },
            Ok((_, Err(e))) => {
                self.error = Some(format!("cannot draw in the window: {e}"));
                event_loop.exit();
            }
            Err(e) => {
                self.error = Some(format!("cannot open a window: {e}; try --headless"));
                event_loop.exit();
            }
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, note: Note) {
        match note {
            Note::Frame => {
                if let Some(w) = &self.window {
                    w.request_redraw();
                }
            }
            Note::Done(error) => {
                self.present();
                if error.is_some() {
                    self.error = error;
                }
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested | WindowEvent::Resized(_) => self.present(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                let name = match &event.logical_key {
                    Key::Named(NamedKey::Escape) => return event_loop.exit(),
                    Key::Named(NamedKey::ArrowLeft) => "left".to_string(),
                    Key::Named(NamedKey::ArrowRight) => "right".to_string(),
                    Key::Named(NamedKey::ArrowUp) => "up".to_string(),
                    Key::Named(NamedKey::ArrowDown) => "down".to_string(),
                    Key::Character(c) => c.to_string(),
                    _ => return,
                };
                if name.eq_ignore_ascii_case("h") {
                    self.show_help = !self.show_help;
                    self.present();
                } else if name.eq_ignore_ascii_case("o") {
                    self.show_readout = !self.show_readout;
                    self.present();
                } else if let Some(a) = action_of_key(&name) {
                    let _ = self.actions.send(a);
                }
            }
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => self.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (self.dragging, self.cursor) {
                    let dx = (position.x - x).round() as i16;
                    let dy = (position.y - y).round() as i16;
                    if dx != 0 || dy != 0 {
                        let _ = self.actions.send(Action::Look(dx, dy));
                    }
                }
                self.cursor = Some((position.x, position.y));
            }
            _ => {}
        }
    }
}
