//! The order plans are served in, fixed when a frame is handed over.
//!
//! A request gets a numbered [`Ticket`] the moment the frame store hands
//! it its frame, under the store's lock: frames in the order they became
//! ready, and the requests one frame answers in the order they arrived.
//! Plans then run one at a time in ticket order. The order cannot be left
//! to the requests' tasks racing for a lock once their frames are in:
//! tokio runs the task woken last first (its LIFO slot), so a request
//! woken by a younger frame arriving right behind an older one took the
//! pool before the older frame's requests, which then waited a whole plan.
//!
//! A ticket whose request is dropped (its connection closed, or the reply
//! lost before it was read) gives up its turn, so no turn waits for a
//! request that will never come.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Mutex, MutexGuard};

use tokio::sync::oneshot;

/// The turns handed out and the ones done.
#[derive(Debug, Default)]
pub struct ServeOrder {
    inner: Mutex<Turns>,
}

#[derive(Debug, Default)]
struct Turns {
    /// The number the next ticket gets.
    next: u64,
    /// The lowest number not yet done: its holder's turn.
    head: u64,
    /// Numbers above `head` already done (their requests dropped early).
    done: BTreeSet<u64>,
    /// Holders waiting for their turn, by number.
    waiting: BTreeMap<u64, oneshot::Sender<()>>,
}

/// One request's place in the serve order; dropping it ends its turn.
#[derive(Debug)]
pub struct Ticket {
    number: u64,
    order: Arc<ServeOrder>,
}

impl ServeOrder {
    pub fn new() -> Arc<Self> {
        Arc::new(ServeOrder::default())
    }

    fn lock(&self) -> MutexGuard<'_, Turns> {
        // Every update leaves the counters consistent, so a poisoned lock
        // is still usable.
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The next place in the order. The frame store issues them while it
    /// holds its own lock, so numbers follow the hand-over order.
    pub fn issue(self: &Arc<Self>) -> Ticket {
        let mut turns = self.lock();
        let number = turns.next;
        turns.next += 1;
        Ticket { number, order: Arc::clone(self) }
    }

    /// Tickets issued and not yet done: plans waiting for their turn or
    /// running.
    pub fn outstanding(&self) -> u64 {
        let turns = self.lock();
        turns.next - turns.head - turns.done.len() as u64
    }

    fn finish(&self, number: u64) {
        let mut turns = self.lock();
        turns.waiting.remove(&number);
        turns.done.insert(number);
        let Turns { head, done, waiting, .. } = &mut *turns;
        while done.remove(head) {
            *head += 1;
        }
        if let Some(next) = waiting.remove(head) {
            // A holder that stopped waiting dropped its ticket, which
            // finished it; a failed send cannot leave a turn hanging.
            let _ = next.send(());
        }
    }
}

impl Ticket {
    /// Waits until every ticket issued before this one is done.
    pub async fn turn(&self) {
        let rx = {
            let mut turns = self.order.lock();
            if turns.head == self.number {
                return;
            }
            let (tx, rx) = oneshot::channel();
            turns.waiting.insert(self.number, tx);
            rx
        };
        // The sender is dropped unsent only with this ticket's entry,
        // which this ticket alone removes: the wait ends at its turn.
        let _ = rx.await;
    }

    pub fn number(&self) -> u64 {
        self.number
    }
}

impl Drop for Ticket {
    fn drop(&mut self) {
        self.order.finish(self.number);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[tokio::test]
    async fn turns_come_in_ticket_order_and_dropped_tickets_give_theirs_up() {
        let order = ServeOrder::new();
        let (first, second, third) = (order.issue(), order.issue(), order.issue());
        let waits_for_both = tokio::spawn(async move {
            third.turn().await;
            third.number()
        });
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert!(!waits_for_both.is_finished(), "the third ticket waited for the first two");
        first.turn().await;
        drop(second);
        tokio::time::sleep(Duration::from_millis(20)).await;
        assert!(!waits_for_both.is_finished(), "the third ticket waited for the first");
        drop(first);
        assert_eq!(tokio::time::timeout(Duration::from_secs(10), waits_for_both).await.unwrap().unwrap(), 2);
        assert_eq!(order.outstanding(), 0);
    }
}
