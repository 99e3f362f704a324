//! One side of the link: a UDP socket that sends MAVLink frames (one per datagram)
//! through the fault injector and returns the valid messages that arrive from the
//! peer's address before a deadline, counting everything else. The peer is either
//! given (the simulator knows the navigation's address; the navigation may be told
//! the simulator's) or latched from the first valid frame of the expected system.

use std::collections::{BTreeMap, VecDeque};
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use mavlink::dialects::common::{ATTITUDE_DATA, HIL_SENSOR_DATA, MavMessage};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::PilsError;
use crate::faults::{FaultInjector, FaultParams, JunkKind};
use crate::frame::{Encoder, Received, Signing, name_of, parse_datagram};
use crate::stats::{Drop, LinkCounters};

/// A wait that the kernel times (the socket's read timeout) ends this long before
/// its deadline, and the rest of it is polled: Linux rounds a read timeout up to its
/// timer tick (a 0.1-2 ms timeout took 8 ms on the development machine, a 5 ms one
/// 12 ms), which made every injected latency and every real-time step due in less
/// than a tick late by up to a tick. 25 ms covers a 100 Hz tick.
const KERNEL_WAIT_MARGIN: Duration = Duration::from_millis(25);

/// The step of the polled part of a wait: a sleep, which the kernel times to tens
/// of microseconds, between non-blocking reads.
const POLL_STEP: Duration = Duration::from_micros(200);

/// How a link finds its peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Peer {
    /// A fixed address: datagrams from any other address are dropped.
    Fixed(SocketAddr),
    /// The source of the first valid frame from the expected system; then fixed.
    Latch,
}

/// Settings of one side.
#[derive(Debug)]
pub struct LinkSetup {
    /// Own system id.
    pub system: u8,
    /// The peer's system id (frames of other systems are unexpected).
    pub peer_system: u8,
    /// Signing for sending and receiving (`None`: unsigned).
    pub signing: Option<([u8; 32], u8)>,
    /// Faults applied to what this side sends.
    pub faults: FaultParams,
    /// Seed of the fault draws.
    pub fault_seed: u64,
}

/// One side of the link (module docs).
#[derive(Debug)]
pub struct Link {
    socket: UdpSocket,
    peer: Peer,
    peer_system: u8,
    encoder: Encoder,
    rx_signing: Option<Signing>,
    injector: FaultInjector,
    rng: ChaCha8Rng,
    held: Option<Vec<u8>>,
    /// Delayed datagrams by release time (ties in sending order).
    pending: BTreeMap<(Instant, u64), Vec<u8>>,
    pending_seq: u64,
    inbox: VecDeque<MavMessage>,
    /// The counters.
    pub counters: LinkCounters,
}

impl Link {
    /// Binds `local` and sets up the side.
    ///
    /// # Errors
    /// [`PilsError::Io`] when the socket cannot be bound; [`PilsError::Setting`] for
    /// bad fault settings.
    pub fn bind(local: SocketAddr, peer: Peer, setup: LinkSetup) -> Result<Self, PilsError> {
        let socket =
            UdpSocket::bind(local).map_err(|e| PilsError::io(format!("bind {local}"), e))?;
        Self::from_socket(socket, peer, setup)
    }

    /// A side on an already bound socket.
    ///
    /// # Errors
    /// As [`Link::bind`].
    pub fn from_socket(socket: UdpSocket, peer: Peer, setup: LinkSetup) -> Result<Self, PilsError> {
        let injector = FaultInjector::new(setup.faults)?;
        let (tx, rx) = match setup.signing {
            Some((key, link_id)) => (
                Some(Signing::new(key, link_id)),
                Some(Signing::new(key, link_id)),
            ),
            None => (None, None),
        };
        Ok(Self {
            socket,
            peer,
            peer_system: setup.peer_system,
            encoder: Encoder::new(setup.system, tx),
            rx_signing: rx,
            injector,
            rng: ChaCha8Rng::seed_from_u64(setup.fault_seed),
            held: None,
            pending: BTreeMap::new(),
            pending_seq: 0,
            inbox: VecDeque::new(),
            counters: LinkCounters::default(),
        })
    }

    /// The bound address.
    ///
    /// # Errors
    /// [`PilsError::Io`] from the socket.
    pub fn local_addr(&self) -> Result<SocketAddr, PilsError> {
        self.socket
            .local_addr()
            .map_err(|e| PilsError::io("local address", e))
    }

    /// The peer's address once known.
    pub fn peer_addr(&self) -> Option<SocketAddr> {
        match self.peer {
            Peer::Fixed(a) => Some(a),
            Peer::Latch => None,
        }
    }

    /// Sends one message (one datagram) through the fault injector. Without a known
    /// peer nothing is sent.
    ///
    /// # Errors
    /// [`PilsError::Io`] when the socket refuses.
    pub fn send(&mut self, m: &MavMessage) -> Result<(), PilsError> {
        let bytes = self.encoder.encode(m);
        self.counters.count_sent(name_of(m));
        if !self.injector.params().any() {
            return self.send_now(&bytes);
        }
        let d = self.injector.decide(&bytes, &mut self.rng);
        if d.copies.is_empty() {
            self.counters.datagrams_lost_injected += 1;
        }
        if d.copies.len() > 1 {
            self.counters.datagrams_duplicated_injected += 1;
        }
        if d.copies.first().is_some_and(|c| c.1 != bytes) {
            self.counters.datagrams_corrupted_injected += 1;
        }
        let now = Instant::now();
        let mut out: Vec<(f64, Vec<u8>)> = d.copies;
        if d.hold_back {
            // Sent after the next datagram: swap with whatever is held.
            let mine = out;
            out = self.held.take().map(|b| vec![(0.0, b)]).unwrap_or_default();
            if let Some((_, b)) = mine.into_iter().next() {
                self.held = Some(b);
            }
        } else if let Some(h) = self.held.take() {
            out.push((0.0, h));
        }
        if let Some(kind) = d.junk {
            let j = self.junk(kind);
            out.push((0.0, j));
            self.counters.junk_sent += 1;
        }
        for (delay, b) in out {
            if delay <= 0.0 {
                self.send_now(&b)?;
            } else {
                let at = now + Duration::from_secs_f64(delay);
                self.pending.insert((at, self.pending_seq), b);
                self.pending_seq += 1;
            }
        }
        Ok(())
    }

    fn send_now(&mut self, bytes: &[u8]) -> Result<(), PilsError> {
        let Some(to) = self.peer_addr() else {
            return Ok(());
        };
        match self.socket.send_to(bytes, to) {
            Ok(_) => {
                self.counters.datagrams_sent += 1;
                Ok(())
            }
            // A peer that is gone (ICMP port unreachable) is found by the timeout.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => Ok(()),
            Err(e) => Err(PilsError::io(format!("send to {to}"), e)),
        }
    }

    /// Sends the delayed datagrams whose time has come.
    ///
    /// # Errors
    /// [`PilsError::Io`] when the socket refuses.
    pub fn flush_due(&mut self) -> Result<(), PilsError> {
        let now = Instant::now();
        while let Some(entry) = self.pending.first_entry() {
            if entry.key().0 > now {
                break;
            }
            let b = entry.remove();
            self.send_now(&b)?;
        }
        Ok(())
    }

    /// Sends everything held or delayed now (end of a run).
    ///
    /// # Errors
    /// [`PilsError::Io`] when the socket refuses.
    pub fn flush_all(&mut self) -> Result<(), PilsError> {
        if let Some(h) = self.held.take() {
            self.send_now(&h)?;
        }
        while let Some((_, b)) = self.pending.pop_first() {
            self.send_now(&b)?;
        }
        Ok(())
    }

    /// The next valid message from the peer before `deadline` (`None` at the
    /// deadline); delayed sends go out meanwhile. A datagram held back for
    /// reordering goes out now: it has been overtaken by the rest of the burst, and
    /// holding it while the sender waits for an answer would turn every reorder into
    /// a loss.
    ///
    /// # Errors
    /// [`PilsError::Io`] when the socket fails.
    pub fn recv(&mut self, deadline: Instant) -> Result<Option<MavMessage>, PilsError> {
        let mut buf = [0u8; 2048];
        if let Some(h) = self.held.take() {
            self.send_now(&h)?;
        }
        loop {
            self.flush_due()?;
            if let Some(m) = self.inbox.pop_front() {
                return Ok(Some(m));
            }
            let now = Instant::now();
            if now >= deadline {
                return Ok(None);
            }
            let mut wait = deadline - now;
            if let Some(((at, _), _)) = self.pending.first_key_value() {
                wait = wait.min(at.saturating_duration_since(now));
            }
            let received = if wait > KERNEL_WAIT_MARGIN {
                self.socket
                    .set_read_timeout(Some(wait - KERNEL_WAIT_MARGIN))
                    .map_err(|e| PilsError::io("set timeout", e))?;
                self.socket.recv_from(&mut buf)
            } else {
                self.poll_once(&mut buf, wait.min(POLL_STEP))?
            };
            match received {
                Ok((n, from)) => self.take_datagram(&buf[..n], from),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock
                            | std::io::ErrorKind::TimedOut
                            | std::io::ErrorKind::ConnectionRefused
                            | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => return Err(PilsError::io("receive", e)),
            }
        }
    }

    /// One non-blocking read; when nothing is there, a sleep of `nap` (the socket is
    /// blocking again on return, for the sends).
    fn poll_once(
        &mut self,
        buf: &mut [u8],
        nap: Duration,
    ) -> Result<std::io::Result<(usize, SocketAddr)>, PilsError> {
        let mode = |socket: &UdpSocket, on: bool| {
            socket
                .set_nonblocking(on)
                .map_err(|e| PilsError::io("set non-blocking", e))
        };
        mode(&self.socket, true)?;
        let received = self.socket.recv_from(buf);
        mode(&self.socket, false)?;
        if matches!(&received, Err(e) if e.kind() == std::io::ErrorKind::WouldBlock) {
            std::thread::sleep(nap);
        }
        Ok(received)
    }

    fn take_datagram(&mut self, bytes: &[u8], from: SocketAddr) {
        self.counters.datagrams_received += 1;
        if let Peer::Fixed(p) = self.peer
            && p != from
        {
            self.counters.count_drop(Drop::ForeignAddress);
            return;
        }
        let mut got: Vec<Received> = Vec::new();
        let counters = &mut self.counters;
        parse_datagram(bytes, self.rx_signing.as_ref(), |r| match r {
            Ok(m) => got.push(m),
            Err(why) => counters.count_drop(why),
        });
        for r in got {
            let name = name_of(&r.message);
            if r.system != u32::from(self.peer_system) {
                self.counters.count_rejected(name, Drop::UnexpectedType);
                continue;
            }
            if self.peer == Peer::Latch {
                self.peer = Peer::Fixed(from);
            }
            self.counters.count_received(name);
            self.inbox.push_back(r.message);
        }
    }

    /// A junk datagram of `kind` (module `faults`).
    fn junk(&mut self, kind: JunkKind) -> Vec<u8> {
        let bogus = MavMessage::HIL_SENSOR(HIL_SENSOR_DATA {
            time_usec: self.rng.random(),
            xacc: 1e6,
            ..HIL_SENSOR_DATA::DEFAULT
        });
        let mut plain = Encoder::new(self.peer_system_of_sender(), None);
        match kind {
            JunkKind::RandomBytes => {
                let n = self.rng.random_range(1..300);
                (0..n).map(|_| self.rng.random()).collect()
            }
            JunkKind::Truncated => {
                let f = plain.encode(&bogus);
                let cut = self.rng.random_range(1..f.len());
                f[..cut].to_vec()
            }
            JunkKind::BadCrc => {
                let mut f = plain.encode(&bogus);
                let n = f.len();
                f[n - 1] ^= 0x5A;
                f
            }
            JunkKind::UnexpectedType => plain.encode(&MavMessage::ATTITUDE(ATTITUDE_DATA::DEFAULT)),
            JunkKind::UnknownId => {
                let mut f = plain.encode(&bogus);
                f[7] = 0xEE;
                f[8] = 0xEE;
                f[9] = 0x0E;
                f
            }
        }
    }

    /// Junk claims to come from this side's own system (as a broken sender would).
    fn peer_system_of_sender(&self) -> u8 {
        self.encoder.system()
    }
}
