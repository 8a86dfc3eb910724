//! What Linux offers a control loop, asked for before a flight on a real drone: the
//! real-time scheduling class (SCHED_FIFO), so that a busy machine's other programs wait for
//! the flight's threads and not the other way round, and memory locked in RAM (`mlockall`),
//! so that no page of the flight is swapped out. Each is granted only when the user may have
//! it (root, CAP_SYS_NICE and CAP_IPC_LOCK, or the limits `ulimit -r` and `ulimit -l`);
//! what was not granted is said, and the flight runs at the normal priority.

/// The SCHED_FIFO priority asked for: above the default of threaded interrupt handlers'
/// neighbours (1–49), below the kernel's own watchdogs (99).
#[cfg(target_os = "linux")]
const FIFO_PRIORITY: i32 = 50;

/// What the system granted.
#[derive(Debug, Default)]
pub struct Granted {
    /// The SCHED_FIFO priority of this thread and of the threads it starts from now on.
    pub fifo_priority: Option<i32>,
    pub memory_locked: bool,
    /// Why each thing not granted was not.
    pub refused: Vec<String>,
}

impl Granted {
    /// One line for the operator.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if let Some(p) = self.fifo_priority {
            parts.push(format!("real-time scheduling (SCHED_FIFO {p})"));
        }
        if self.memory_locked {
            parts.push("memory locked".into());
        }
        let mut s = if parts.is_empty() {
            "the flight runs at the normal priority".to_string()
        } else {
            format!("the flight runs with {}", parts.join(" and "))
        };
        if !self.refused.is_empty() {
            s += &format!(" ({})", self.refused.join("; "));
        }
        s
    }
}

/// Asks for SCHED_FIFO for this thread (and the threads it starts from now on) and for all of
/// the process's memory locked.
#[cfg(target_os = "linux")]
pub fn request() -> Granted {
    let mut g = Granted::default();
    let param = libc::sched_param {
        sched_priority: FIFO_PRIORITY,
    };
    // SAFETY: sched_setscheduler with pid 0 acts on the calling thread; `param` is a valid
    // sched_param for the call's duration.
    if unsafe { libc::sched_setscheduler(0, libc::SCHED_FIFO, &param) } == 0 {
        g.fifo_priority = Some(FIFO_PRIORITY);
    } else {
        g.refused.push(format!(
            "no real-time scheduling: {}",
            std::io::Error::last_os_error()
        ));
    }
    // SAFETY: mlockall takes flags only.
    if unsafe { libc::mlockall(libc::MCL_CURRENT | libc::MCL_FUTURE) } == 0 {
        g.memory_locked = true;
    } else {
        g.refused.push(format!(
            "memory not locked: {}",
            std::io::Error::last_os_error()
        ));
    }
    g
}

/// Elsewhere: nothing is asked for.
#[cfg(not(target_os = "linux"))]
pub fn request() -> Granted {
    Granted {
        refused: vec!["real-time scheduling is asked for on Linux only".into()],
        ..Granted::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The line says what was granted and why the rest was not.
    #[test]
    fn the_operator_is_told_what_was_granted() {
        let g = Granted {
            fifo_priority: Some(50),
            memory_locked: false,
            refused: vec!["memory not locked: Operation not permitted".into()],
        };
        assert_eq!(
            g.describe(),
            "the flight runs with real-time scheduling (SCHED_FIFO 50) (memory not locked: \
             Operation not permitted)"
        );
        assert_eq!(
            Granted::default().describe(),
            "the flight runs at the normal priority"
        );
    }
}
