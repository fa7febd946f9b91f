//! The 4-operator Blocks World's words, which the problem reader, the domain reader and the
//! plan share: facts and their predicates, the four operators and the names a domain file
//! gives them, and the ground actions with the facts each needs and makes
//! ([`Action::conditions`], the one home of the domain's rules).

/// A fact of the 4-operator domain, its blocks by index into [`Problem::block_names`](super::Problem::block_names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fact {
    /// `(on x y)`: `x` stands on `y`.
    On(usize, usize),
    /// `(on-table x)`.
    OnTable(usize),
    /// `(clear x)`: nothing stands on `x` (and it is not held).
    Clear(usize),
    /// `(arm-empty)`.
    ArmEmpty,
    /// `(holding x)`.
    Holding(usize),
}

/// A predicate of the 4-operator domain, whatever the file calls it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) enum Predicate {
    On,
    OnTable,
    Clear,
    ArmEmpty,
    Holding,
}

impl Predicate {
    /// The predicate a (lower-case) name spells: the competition's names, or the 2000
    /// competition's `ontable` and `handempty`, which mean the same.
    pub(crate) fn of_name(name: &str) -> Option<Predicate> {
        Some(match name {
            "on" => Predicate::On,
            "on-table" | "ontable" => Predicate::OnTable,
            "clear" => Predicate::Clear,
            "arm-empty" | "handempty" => Predicate::ArmEmpty,
            "holding" => Predicate::Holding,
            _ => return None,
        })
    }

    /// Its number of blocks.
    pub(crate) fn arity(self) -> usize {
        match self {
            Predicate::On => 2,
            Predicate::OnTable | Predicate::Clear | Predicate::Holding => 1,
            Predicate::ArmEmpty => 0,
        }
    }

    /// The fact of this predicate over `args` (as many as [`Predicate::arity`]).
    pub(crate) fn fact(self, args: &[usize]) -> Fact {
        match self {
            Predicate::On => Fact::On(args[0], args[1]),
            Predicate::OnTable => Fact::OnTable(args[0]),
            Predicate::Clear => Fact::Clear(args[0]),
            Predicate::ArmEmpty => Fact::ArmEmpty,
            Predicate::Holding => Fact::Holding(args[0]),
        }
    }
}

impl Fact {
    /// The fact as PDDL, with the blocks' names: `(on b3 b5)`.
    pub fn to_pddl(self, names: &[String]) -> String {
        match self {
            Fact::On(x, y) => format!("(on {} {})", names[x], names[y]),
            Fact::OnTable(x) => format!("(on-table {})", names[x]),
            Fact::Clear(x) => format!("(clear {})", names[x]),
            Fact::ArmEmpty => "(arm-empty)".into(),
            Fact::Holding(x) => format!("(holding {})", names[x]),
        }
    }
}

/// One of the domain's four actions, whatever the file calls it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Operator {
    /// Take a clear block from the table.
    Pickup,
    /// Put the held block on the table.
    Putdown,
    /// Put the held block on a clear block.
    Stack,
    /// Take a clear block from the block it stands on.
    Unstack,
}

impl Operator {
    /// The four, in the order the tables of this module list them.
    pub const ALL: [Operator; 4] = [Operator::Pickup, Operator::Putdown, Operator::Stack, Operator::Unstack];

    /// The names a file may give it (lower case).
    pub(crate) fn spellings(self) -> &'static [&'static str] {
        match self {
            Operator::Pickup => &["pickup", "pick-up"],
            Operator::Putdown => &["putdown", "put-down"],
            Operator::Stack => &["stack"],
            Operator::Unstack => &["unstack"],
        }
    }

    /// The operator a name spells, in either spelling.
    pub fn of_name(name: &str) -> Option<Operator> {
        let name = name.to_lowercase();
        Operator::ALL
            .into_iter()
            .find(|op| op.spellings().contains(&name.as_str()))
    }

    /// Its number of parameters.
    pub fn arity(self) -> usize {
        match self {
            Operator::Pickup | Operator::Putdown => 1,
            Operator::Stack | Operator::Unstack => 2,
        }
    }

    /// The action with parameter `i` standing for block `i`: the schema
    /// [`Action::conditions`] instantiates.
    pub(crate) fn schema(self) -> Action {
        match self {
            Operator::Pickup => Action::Pickup(0),
            Operator::Putdown => Action::Putdown(0),
            Operator::Stack => Action::Stack(0, 1),
            Operator::Unstack => Action::Unstack(0, 1),
        }
    }
}

/// The names a plan gives the four actions: the domain file's, as it spells them.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct ActionNames(pub(crate) [String; 4]);

impl Default for ActionNames {
    /// `pickup`, `putdown`, `stack`, `unstack`: the competition's spelling, used when no
    /// domain file is given.
    fn default() -> Self {
        ActionNames(Operator::ALL.map(|op| op.spellings()[0].to_string()))
    }
}

impl ActionNames {
    /// The name of `op`.
    pub fn of(&self, op: Operator) -> &str {
        &self.0[op as usize]
    }
}

/// One action of the 4-operator domain; blocks by index into [`Problem::block_names`](super::Problem::block_names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    /// `(pickup x)`: take the clear block `x` from the table.
    Pickup(usize),
    /// `(putdown x)`: put the held block `x` on the table.
    Putdown(usize),
    /// `(stack x y)`: put the held block `x` on the clear block `y`.
    Stack(usize, usize),
    /// `(unstack x y)`: take the clear block `x` from `y`.
    Unstack(usize, usize),
}

/// An action's precondition and effects, as facts over its blocks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Conditions {
    /// What must hold before.
    pub pre: Vec<Fact>,
    /// What holds after.
    pub add: Vec<Fact>,
    /// What no longer holds after (deleted before the adds, as STRIPS does).
    pub del: Vec<Fact>,
}

impl Action {
    /// Which of the four it is.
    pub fn operator(self) -> Operator {
        match self {
            Action::Pickup(_) => Operator::Pickup,
            Action::Putdown(_) => Operator::Putdown,
            Action::Stack(..) => Operator::Stack,
            Action::Unstack(..) => Operator::Unstack,
        }
    }

    /// The action as PDDL, with the blocks' names and the domain's action names: `(stack
    /// b4 b3)`.
    pub fn to_pddl(self, blocks: &[String], actions: &ActionNames) -> String {
        let name = actions.of(self.operator());
        match self {
            Action::Pickup(x) | Action::Putdown(x) => format!("({name} {})", blocks[x]),
            Action::Stack(x, y) | Action::Unstack(x, y) => format!("({name} {} {})", blocks[x], blocks[y]),
        }
    }

    /// Its precondition and effects: the 4-operator domain's rules, which the replay
    /// applies and a domain file is checked against ([`super::Domain`]).
    pub fn conditions(self) -> Conditions {
        match self {
            Action::Pickup(x) => Conditions {
                pre: vec![Fact::Clear(x), Fact::OnTable(x), Fact::ArmEmpty],
                add: vec![Fact::Holding(x)],
                del: vec![Fact::Clear(x), Fact::OnTable(x), Fact::ArmEmpty],
            },
            Action::Putdown(x) => Conditions {
                pre: vec![Fact::Holding(x)],
                add: vec![Fact::Clear(x), Fact::ArmEmpty, Fact::OnTable(x)],
                del: vec![Fact::Holding(x)],
            },
            Action::Stack(x, y) => Conditions {
                pre: vec![Fact::Clear(y), Fact::Holding(x)],
                add: vec![Fact::ArmEmpty, Fact::Clear(x), Fact::On(x, y)],
                del: vec![Fact::Clear(y), Fact::Holding(x)],
            },
            Action::Unstack(x, y) => Conditions {
                pre: vec![Fact::On(x, y), Fact::Clear(x), Fact::ArmEmpty],
                add: vec![Fact::Holding(x), Fact::Clear(y)],
                del: vec![Fact::On(x, y), Fact::Clear(x), Fact::ArmEmpty],
            },
        }
    }
}
