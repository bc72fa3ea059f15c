!> The scene schema's building blocks: the kinds of input values, the groups of a scene file
!> and the declaration of one variable (io_schema has the whole table and its queries).
module io_schema_types
  use core_kinds, only: wp
  implicit none
  private
  public :: var_spec_t, SCENE_GROUPS, SINGLE_GROUPS
  public :: VK_REAL, VK_INT, VK_LOGICAL, VK_STRING, VK_CHOICE, VK_REAL_LIST, VK_STRING_LIST, &
    VK_CHOICE_LIST

  integer, parameter :: VK_REAL = 1, VK_INT = 2, VK_LOGICAL = 3, VK_STRING = 4, VK_CHOICE = 5, &
    VK_REAL_LIST = 6, VK_STRING_LIST = 7, VK_CHOICE_LIST = 8

  !> Groups of a scene file, and those that may appear at most once.
  character(len=10), parameter :: SCENE_GROUPS(17) = [character(len=10) :: 'scene', 'node', &
    'link', 'hinge', 'truss', 'slider', 'mass', 'force', 'motion', 'controller', 'static', &
    'modal', 'buckling', 'linear', 'dynamic', 'reduction', 'output']
  character(len=10), parameter :: SINGLE_GROUPS(8) = [character(len=10) :: 'scene', 'static', &
    'modal', 'buckling', 'linear', 'dynamic', 'reduction', 'output']

  !> One variable. `default` is the text shown in docs ('' with `required`; a word such as
  !> 'law' where it depends on other variables); numbers are parsed from it. The range is
  !> lower <= x <= upper, with strict inequalities where *_open; keyword values (and whole
  !> numbers with a fixed set, erk_order) list their `choices` separated by '|'.
  type :: var_spec_t
    character(len=10) :: group
    character(len=18) :: name
    integer :: kind
    character(len=12) :: units
    character(len=16) :: default
    logical :: required
    real(wp) :: lower
    logical :: lower_open
    real(wp) :: upper
    logical :: upper_open
    character(len=72) :: choices
    character(len=56) :: doc
  end type var_spec_t

end module io_schema_types
