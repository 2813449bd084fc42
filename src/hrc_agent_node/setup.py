from setuptools import find_packages, setup

package_name = 'hrc_agent_node'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/params', [
            '../../params/agent.yaml',
            '../../params/task_tree.yaml',
            '../../params/cases.yaml',
        ]),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='PPO robot agent: task decomposition tree, hierarchical reward, learning '
                'strategies, checkpoints, and the agent node.',
    license='Apache-2.0',
    entry_points={'console_scripts': [
        'agent_node = hrc_agent_node.agent_node:main',
    ]},
)
